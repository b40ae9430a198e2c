// libFuzzer harness: the whole scene compiler on one file (a TOML scene, an I♥IQ document or a module file,
// told apart by their content), for one of the three targets, through glslang's validation. Exit 0 or 1
// are both fine; exit 3 (GLSL that glslang rejects: a bug in iqc) aborts, as a crash does.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "scene/Compile.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    using namespace iqc;
    namespace fs = std::filesystem;
    static const fs::path dir = [] {
        fs::path d = fs::temp_directory_path() / ("iqc_fuzz_scene_" + std::to_string(::getpid()));
        fs::create_directories(d);
        return d;
    }();
    std::string text(reinterpret_cast<const char*>(data), size);
    const char* ext = text.find("```") != std::string::npos ? ".md"
                      : text.find("[[shapes]]") != std::string::npos || text.find("[camera]") != std::string::npos ? ".iq"
                                                                                                                    : ".iql";
    fs::path path = dir / (std::string("input") + ext);
    {
        std::ofstream out(path, std::ios::binary | std::ios::trunc);
        out.write(text.data(), std::streamsize(text.size()));
    }
    SourceManager sm;
    Diagnostics diags(sm);
    CompileOptions opts;
    // Every target but hlsl (its SPIRV-Cross pass is the spirv target's module, already covered).
    const Target targets[] = {Target::Shadertoy, Target::WebGL2, Target::GLSL330, Target::SPIRV, Target::ThreeJS};
    opts.target = targets[size % 5];
    CompileResult r = compile_file(path.string(), sm, diags, opts);
    std::string rendered = diags.render();
    if (r.exit_code == 3) {
        std::fprintf(stderr, "%s\n%s\n", rendered.c_str(), r.internal.c_str());
        std::abort();
    }
    if (r.exit_code != 0 && r.exit_code != 1) std::abort();
    return 0;
}
