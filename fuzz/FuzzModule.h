// What the module harnesses share: one fuzz input as a module file in a fresh source manager, with a
// module library (the standard library for imports) reporting to fresh diagnostics.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include "scene/Modules.h"

namespace iqc::fuzz {

struct FuzzModule {
    SourceManager sm;
    Diagnostics diags{sm};
    ModuleSource src;
    ModuleLibrary lib{sm, diags};

    FuzzModule(const uint8_t* data, size_t size) {
        std::string text(reinterpret_cast<const char*>(data), size);
        src.name = "fuzz";
        src.file = sm.add("fuzz.iql", std::move(text));
        src.ranges = {{0, uint32_t(size)}};
        src.where = {src.file, 0, 1};
        src.origin = "document";
    }
};

}  // namespace iqc::fuzz
