// iqc: the command line. Compiles I♥IQ documents and scenes to fragment shaders.
//
// Exit codes: 0 success; 1 a diagnostic about the input; 2 usage; 3 internal error (a bug in iqc, such as
// generated GLSL that glslang rejects; nothing is written then).
#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fmt/format.h>
#include <fstream>
#include <iostream>

#include "scene/Compile.h"

namespace {

int write_output(const std::string& path, const std::string& text) {
    if (path.empty() || path == "-") {
        std::fwrite(text.data(), 1, text.size(), stdout);
        return 0;
    }
    std::string tmp = path + ".iqc-tmp";
    {
        std::ofstream out(tmp, std::ios::binary);
        if (!out || !(out << text) || !(out.flush())) {
            std::fprintf(stderr, "iqc: error: cannot write '%s'\n", path.c_str());
            std::remove(tmp.c_str());
            return 1;
        }
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        std::fprintf(stderr, "iqc: error: cannot write '%s'\n", path.c_str());
        std::remove(tmp.c_str());
        return 1;
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    CLI::App app{
        "iqc — compiles math written as papers print it (I♥LA / I♥IQ) and a scene into a standalone fragment "
        "shader.\n\n"
        "Inputs: an I♥IQ document (.md: '❤: name' lines name ```iheartla blocks, one ```scene block holds the TOML "
        "scene), a TOML scene (.iq) with inline [modules], or a shape module file (.iql, shown alone).\n\n"
        "Examples:\n"
        "  iqc examples/two_tori.md -o out.frag      # Shadertoy code, paste into shadertoy.com/new\n"
        "  iqc scene.iq --dump-ir                   # print the IR and the shader\n\n"
        "Exit codes: 0 ok, 1 error in the input, 2 usage, 3 internal error (a bug in iqc).",
        "iqc"};
    app.set_version_flag("--version", std::string("iqc ") + IQC_VERSION);
    std::string input, output, target = "shadertoy";
    bool dump_ir = false, time = false;
    app.add_option("input", input, "scene (.iq), document (.md) or shape module (.iql)")->required();
    app.add_option("-o,--output", output, "where to write the shader (default: standard output)");
    app.add_option("--target", target, "output kind: shadertoy (default)")
        ->check(CLI::IsMember({"shadertoy"}));
    app.add_flag("--dump-ir", dump_ir, "print the typed IR of every function to standard error");
    app.add_flag("--time", time, "print the compile time to standard error");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        int code = app.exit(e);
        return e.get_exit_code() == 0 ? 0 : (code == 0 ? 0 : 2);
    }
    auto t0 = std::chrono::steady_clock::now();
    iqc::SourceManager sm;
    iqc::Diagnostics diags(sm);
    iqc::CompileOptions opts;
    opts.dump_ir = dump_ir;
    iqc::CompileResult r = iqc::compile_file(input, sm, diags, opts);
    std::string rendered = diags.render();
    if (!rendered.empty()) std::fputs(rendered.c_str(), stderr);
    if (dump_ir && !r.ir.empty()) std::fputs(r.ir.c_str(), stderr);
    if (r.exit_code == 3) {
        std::fprintf(stderr, "%s\n", r.internal.c_str());
        return 3;
    }
    if (r.exit_code != 0) {
        if (diags.error_count() > 1) std::fprintf(stderr, "%zu errors\n", diags.error_count());
        return 1;
    }
    int rc = write_output(output, r.code);
    if (time) {
        double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        std::fprintf(stderr, "iqc: compiled in %.2f ms\n", ms);
    }
    if (rc == 0 && !output.empty() && output != "-") std::fprintf(stderr, "iqc: wrote %s\n", output.c_str());
    return rc;
}
