// Files from runtime_templates/ and stdlib/ compiled into the iqc binary (see cmake/embed.cmake),
// so that an installed iqc needs no data directory.
#pragma once

#include <optional>
#include <string_view>
#include <vector>

namespace iqc {

struct EmbeddedFile {
    std::string_view path;      // relative to the repository root, e.g. "stdlib/transformations.iql"
    std::string_view contents;
};

const std::vector<EmbeddedFile>& embedded_resources();

// The contents of an embedded file by its path, if any.
inline std::optional<std::string_view> embedded_file(std::string_view path) {
    for (const auto& f : embedded_resources())
        if (f.path == path) return f.contents;
    return std::nullopt;
}

}  // namespace iqc
