// iqc: the command line. Compiles I♥IQ documents and scenes to fragment shaders.
//
// Exit codes: 0 success; 1 a diagnostic about the input; 2 usage; 3 internal error (a bug in iqc, such as
// generated GLSL that glslang rejects; nothing is written then).
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <functional>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <cerrno>
#include <malloc.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <fmt/format.h>
#include <fstream>
#include <filesystem>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <iostream>

#include "render/Png.h"
#include "render/Render.h"
#include "glsl/ShadertoyWrapper.h"
#include "glsl/Names.h"
#include "glsl/Validate.h"
#include "glsl/Wgsl.h"
#include "bench/Bench.h"
#include "driver/Serve.h"
#include "scene/Page.h"
#include "scene/CppHeader.h"
#include "scene/ThreeModule.h"
#include "scene/Compile.h"
#include "scene/Evaluate.h"
#include "ir/Pipeline.h"
#include "source/Internal.h"

namespace {

// The front end allocates many small nodes; in a fresh process most of its time went to page faults
// (14,000 for a 5,000-line module). Growing the heap in large steps backed by transparent huge pages
// (where the kernel allows it on request) cuts that to a few hundred. Harmless where unsupported.
void tune_allocator() {
#if defined(__GLIBC__) && defined(M_TOP_PAD)
    const size_t pad = size_t(64) << 20;
    mallopt(M_TOP_PAD, int(pad));
    mallopt(M_TRIM_THRESHOLD, int(pad * 4));  // keep what is freed for reuse
    mallopt(M_MMAP_THRESHOLD, int(pad * 2));  // large vectors come from the same heap
    // Grow the heap once by `pad`, mark that range for huge pages, and give it back to malloc.
    void* probe = std::malloc(pad);
    if (!probe) return;
    char* top = static_cast<char*>(sbrk(0));
    const uintptr_t huge = uintptr_t(2) << 20;
    uintptr_t begin = (reinterpret_cast<uintptr_t>(probe) + huge - 1) & ~(huge - 1);
    uintptr_t end = reinterpret_cast<uintptr_t>(top) & ~(huge - 1);
    if (end > begin) madvise(reinterpret_cast<void*>(begin), end - begin, MADV_HUGEPAGE);
    std::free(probe);
#endif
}

// The PNG path of frame k of an animation: out.png -> out_0007.png.
std::string printable(const std::string& s);
void put(std::FILE* f, std::string_view text);

// Runs `work` in a child process (its output discarded) and says how it died ("" when it did not). A shader a user
// wrote by hand goes to third-party compilers (glslang, Mesa's) whose recursion a long enough expression
// overflows (a sum of 20,000 terms: a segfault in the driver): tried in a child first, such a crash becomes a
// diagnostic instead of iqc's death. Call before any thread or GL context exists.
std::string crash_in_child(const std::function<void()>& work) {
    std::fflush(stdout);
    std::fflush(stderr);
    pid_t pid = fork();
    if (pid < 0) return "";  // no child: go on without the check
    if (pid == 0) {
        struct rlimit none = {0, 0};
        setrlimit(RLIMIT_CORE, &none);  // no core file for the crash this is here to catch
        int null = open("/dev/null", O_WRONLY);
        if (null >= 0) {
            dup2(null, 1);
            dup2(null, 2);
        }
        work();
        _exit(0);
    }
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    // A signal, or (a sanitizer's handler reports the overflow and exits) a status `work` never ends with.
    if (WIFSIGNALED(status)) return fmt::format("signal {}, {}", WTERMSIG(status), strsignal(WTERMSIG(status)));
    if (WIFEXITED(status) && WEXITSTATUS(status) != 0) return fmt::format("exit status {}", WEXITSTATUS(status));
    return "";
}

// The diagnostic for a hand-written shader that crashed a third-party compiler (crash_in_child).
int report_compiler_crash(const std::string& path, const char* compiler, const std::string& how) {
    std::fprintf(stderr, "iqc: error: %s: %s crashed compiling this shader (%s): an expression or a chain of "
                         "operators too long or too deeply nested for its compiler; split it into statements\n",
                 printable(path).c_str(), compiler, how.c_str());
    return 1;
}

std::string frame_path(const std::string& out, int k, int frames) {
    namespace fs = std::filesystem;
    if (frames <= 1) return out;
    std::error_code ec;
    if (fs::exists(out, ec) && !fs::is_regular_file(out, ec) && !fs::is_directory(out, ec)) return out;  // a device: every frame to it
    // The number goes before the file name's extension, not the path's last dot (`-o v1.2/x` wrote into
    // `v1_0000.2/`, `-o ./anim` tried `_0000./anim`; a new user's trial).
    fs::path p(out);
    std::string ext = p.extension().string();
    std::string name = p.stem().string() + fmt::format("_{:04d}", k) + (ext.empty() ? ".png" : ext);
    return (p.parent_path() / name).string();
}

// Whether writing `out` (given as `flag`) would overwrite a file the compile read (`inputs`: the scene, the
// modules and documents it includes, a rendered shader): the same file by path, or by identity (a link). Prints
// the error and returns true: the user's sources are never replaced by an output (a scene by its PNG, an
// included module by the shader; found by a new user's trial).
bool overwrites_input(const std::string& flag, const std::string& out, const std::vector<std::string>& inputs) {
    namespace fs = std::filesystem;
    if (out.empty() || out == "-") return false;
    std::error_code ec;
    if (!fs::exists(out, ec) || !fs::is_regular_file(out, ec)) return false;  // nothing there yet, or a device
    for (const auto& in : inputs) {
        std::error_code e2;
        if (fs::equivalent(out, in, e2) && !e2) {
            std::fprintf(stderr, "iqc: error: %s '%s' is a file this command reads ('%s'): it would be overwritten; give "
                                 "another output path\n",
                         flag.c_str(), printable(out).c_str(), printable(in).c_str());
            return true;
        }
    }
    return false;
}

double percentile(std::vector<float> v, double q) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[size_t(q * double(v.size() - 1) + 0.5)];
}

int render_command(const std::string& code, const iqc::ShaderInputs& inputs, bool webgl2, const std::string& output, const std::string& size, float time, int frames, float fps, bool stats,
                   bool quiet, const std::function<iqc::CompileResult()>& instrumented, const std::string& user_path = "",
                   const std::string* user_code = nullptr) {
    iqc::render::RenderOptions ro;
    char rest = 0;
    if (std::sscanf(size.c_str(), "%dx%d%c", &ro.width, &ro.height, &rest) != 2 || ro.width < 1 || ro.height < 1) {
        std::fprintf(stderr, "iqc: error: --size must look like 640x360\n");
        return 2;
    }
    // At most 4096 pixels a side and 16 megapixels: the float image and its copies stay within 1 GB, and the
    // software renderer within seconds per frame.
    if (ro.width > 4096 || ro.height > 4096) {
        std::fprintf(stderr, "iqc: error: --size %dx%d is too large: at most 4096x4096\n", ro.width, ro.height);
        return 2;
    }
    if (!std::isfinite(time) || !std::isfinite(fps)) {
        std::fprintf(stderr, "iqc: error: --time and --fps must be finite numbers\n");
        return 2;
    }
    // Each finite, they could still give the last frame a time past 32-bit floats (iTime = ∞: --fps 1e-45).
    if (double last = double(time) + double(std::max(frames, 1) - 1) / double(fps); !(std::fabs(last) <= 3.4e38)) {
        std::fprintf(stderr, "iqc: error: --time, --frames and --fps put the last frame at %g s, past 32-bit floats\n", last);
        return 2;
    }
    if (output.empty() || output == "-") {  // it wrote a file named '-'
        std::fprintf(stderr, "iqc: error: render writes PNG files: give one with -o (standard output is not one)\n");
        return 2;
    }
    for (const auto& u : inputs.all_uniforms()) {
        if (u.integer) ro.int_uniforms.push_back({u.name, int(u.value[0])});
        else ro.uniforms.push_back({u.name, std::vector<float>(u.value.begin(), u.value.end())});
    }
    for (const auto& b : inputs.blocks) ro.uniform_blocks.push_back({b.name, b.binding, b.bytes});
    ro.data_texture = {inputs.texture.name, inputs.texture.width, inputs.texture.height, inputs.texture.rgba};
    std::string source = webgl2 ? code : iqc::glsl::wrap_shadertoy(code);
    std::string err;
    auto renderer = iqc::render::Renderer::create(&err);
    if (!renderer) {
        std::fprintf(stderr, "iqc: error: no headless renderer: %s\n", err.c_str());
        return 1;
    }
    bool tty = isatty(2);
    long long pixels = (long long)ro.width * ro.height;
    if (pixels > 2000000) ro.band_rows = std::max(1, int(400000 / ro.width));  // long renders: bands, with progress
    if (tty && ro.band_rows > 0)
        ro.progress = [&](int done, int total) { std::fprintf(stderr, "\riqc: rendering %3d%%", 100 * done / total); };
    iqc::render::RenderResult last;
    std::vector<double> frame_ms;
    double first_compile_ms = 0;
    // The output's folder is made as needed (`--frames 8 -o frames/a.png` into a new frames/).
    if (auto dir = std::filesystem::path(output).parent_path(); !dir.empty()) {
        std::error_code ec;
        std::filesystem::create_directories(dir, ec);
        if (ec) {
            std::fprintf(stderr, "iqc: error: cannot create the folder '%s' for the PNG: %s\n", printable(dir.string()).c_str(),
                         ec.message().c_str());
            return 1;
        }
    }
    for (int k = 0; k < frames; ++k) {
        ro.time = time + float(k) / fps;
        ro.frame = k;
        last = renderer->render(source, ro);
        if (!last.ok) {
            // A shader the user wrote: the driver's messages at FILE:LINE:COL, with the line and a caret.
            const std::string head = "fragment shader compile failed:\n";
            if (user_code && last.error.rfind(head, 0) == 0) {
                iqc::SourceManager sm;
                iqc::Diagnostics diags(sm);
                iqc::FileId f = sm.add(user_path, *user_code);
                if (iqc::glsl::locate_shader_log(last.error.substr(head.size()), f, diags) > 0) {
                    put(stderr, std::string(tty ? "\n" : "") + diags.render());
                    return 1;
                }
            }
            std::fprintf(stderr, "%siqc: error: rendering failed: %s\n", tty ? "\n" : "", last.error.c_str());
            return 1;
        }
        frame_ms.push_back(last.frame_ms);
        if (k == 0) first_compile_ms = last.compile_ms;
        std::string path = frame_path(output, k, frames);
        if (!iqc::render::write_png(path, last.image, &err)) {
            std::fprintf(stderr, "iqc: error: %s\n", err.c_str());
            return 1;
        }
        if (frames > 1 && tty) std::fprintf(stderr, "\riqc: frame %d/%d", k + 1, frames);
    }
    if (tty && (frames > 1 || ro.band_rows > 0)) std::fprintf(stderr, "\n");
    // The first frame includes the driver's lazy compilation (llvmpipe compiles at the first draw).
    double first_ms = frame_ms[0];
    std::vector<double> later(frame_ms.begin() + 1, frame_ms.end());
    std::sort(later.begin(), later.end());
    std::sort(frame_ms.begin(), frame_ms.end());
    // Milliseconds to three decimals below 10 ms (a GPU draws a frame in well under one), else to one.
    auto ms = [](double v) { return v < 10 ? fmt::format("{:.3f}", v) : fmt::format("{:.1f}", v); };
    std::string later_text = later.empty() ? "" : ", later frames " + ms(later[later.size() / 2]) + " ms median";
    // The compile is the first frame's (the later frames reuse its program; before, the last frame's ~0 ms
    // was printed and a driver's link time was left out of every figure).
    if (!quiet)
    std::fprintf(stderr, "iqc: rendered %s (%dx%d%s, %s, shader compile %s ms, frame %s ms%s)\n",
                 frame_path(output, 0, frames).c_str(), ro.width, ro.height,
                 frames > 1 ? fmt::format(", {} frames", frames).c_str() : "", last.renderer.c_str(),
                 ms(first_compile_ms).c_str(), ms(first_ms).c_str(), later_text.c_str());
    if (!stats) return 0;
    // NaN/Inf in the colour image, and the instrumented build's counts.
    long nan = 0;
    for (int y = 0; y < last.image.height; ++y)
        for (int x = 0; x < last.image.width; ++x) {
            const float* p = last.image.pixel(x, y);
            nan += !(std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]) && std::isfinite(p[3]));
        }
    iqc::CompileResult ic = instrumented();
    if (ic.exit_code != 0) {
        // The scene compiled without the counters: a failure here is iqc's, and says what it was.
        std::fprintf(stderr, "iqc: internal compiler error: the instrumented shader (--stats) failed to compile (this is a bug in "
                             "iqc):\n%s\n", ic.internal.c_str());
        return 3;
    }
    iqc::render::RenderOptions io = ro;
    io.progress = nullptr;
    io.time = time;
    io.frame = 0;
    std::string isource = webgl2 ? ic.code : iqc::glsl::wrap_shadertoy(ic.code);
    iqc::render::RenderResult ir = renderer->render(isource, io);
    if (!ir.ok) {
        std::fprintf(stderr, "iqc: error: rendering the instrumented shader failed: %s\n", ir.error.c_str());
        return 1;
    }
    std::vector<float> steps, evals, shape_evals;
    long flagged = 0, bad_distances = 0;
    double bounds = 0;
    for (int y = 0; y < ir.image.height; ++y)
        for (int x = 0; x < ir.image.width; ++x) {
            const float* p = ir.image.pixel(x, y);
            steps.push_back(p[0]);
            evals.push_back(p[1]);
            shape_evals.push_back(p[3]);
            int flags = std::isfinite(p[2]) ? int(p[2] + 0.5f) : 1;
            flagged += (flags & 1) != 0;
            bad_distances += (flags & 2) != 0;
            bounds += double(flags >> 2);
        }
    double sm = 0, em = 0;
    for (float v : steps) sm += v;
    for (float v : evals) em += v;
    std::printf("nan_pixels: %ld\n", std::max(nan, flagged));
    std::printf("nan_distance_pixels: %ld\n", bad_distances);
    std::printf("steps_mean: %.3f\n", sm / double(steps.size()));
    std::printf("steps_p99: %.0f\n", percentile(steps, 0.99));
    std::printf("evals_mean: %.3f\n", em / double(evals.size()));
    std::printf("evals_p99: %.0f\n", percentile(evals, 0.99));
    double se = 0;
    for (float v : shape_evals) se += v;
    std::printf("shape_evals_mean: %.3f\n", se / double(shape_evals.size()));
    std::printf("shape_evals_per_eval: %.3f\n", em > 0 ? se / em : 0.0);
    std::printf("segment_bounds_mean: %.3f\n", bounds / double(evals.size()));
    std::printf("frame_ms: %.3f\n", frame_ms[frame_ms.size() / 2]);
    std::printf("compile_ms: %.3f\n", last.compile_ms);
    std::printf("renderer: %s\n", last.renderer.c_str());
    return 0;
}

// Writes text with its length (a NUL byte in a diagnostic's source line must not cut off what follows).
void put(std::FILE* f, std::string_view text) { std::fwrite(text.data(), 1, text.size(), f); }

// Outputs written together (the shader, --meta, --depfile; bench's CSV and plot), all or none: every regular
// file (or new one) is first written to a temporary file beside it, then standard output ("" or "-") and
// anything else that exists and is not a regular file (a device such as /dev/null, a FIFO, a symbolic link:
// a rename would replace it) is written in place, and only when all of that succeeded are the temporary
// files renamed over their outputs — so a reader never sees half a file, and a failing output (a full disk,
// /dev/full) leaves the others as they were. A regular file that already holds exactly its bytes is left
// alone (its modification time too: a build system then rebuilds nothing downstream). Every write error is
// reported: commit() returns 1.
class OutputSet {
public:
    // Returns the output's index (for changed()).
    size_t add(std::string path, std::string text) {
        Item it;
        it.path = std::move(path);
        it.text = std::move(text);
        items_.push_back(std::move(it));
        return items_.size() - 1;
    }
    // Whether output i's bytes were written (false: a regular file that already held them).
    bool changed(size_t i) const { return items_[i].changed; }

    int commit() {
        namespace fs = std::filesystem;
        for (Item& it : items_) {  // temporaries for regular files
            if (it.path.empty() || it.path == "-") {
                it.direct = true;
                continue;
            }
            std::error_code ec;
            fs::file_status st = fs::symlink_status(it.path, ec);
            if (!ec && fs::exists(st) && !fs::is_regular_file(st)) {
                if (fs::is_directory(fs::status(it.path, ec))) return fail(it, "it is a directory");
                it.direct = true;
                continue;
            }
            {
                std::ifstream in(it.path, std::ios::binary);
                if (in) {
                    std::string old((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
                    if (!in.bad() && old == it.text) {
                        it.changed = false;
                        continue;
                    }
                }
            }
            it.tmp = it.path + ".iqc-tmp";
            std::ofstream out(it.tmp, std::ios::binary);
            if (!out || !(out << it.text) || !(out.flush())) return fail(it, std::strerror(errno));
        }
        for (Item& it : items_) {  // in place: standard output, devices
            if (!it.direct) continue;
            if (it.path.empty() || it.path == "-") {
                if (std::fwrite(it.text.data(), 1, it.text.size(), stdout) != it.text.size() || std::fflush(stdout) != 0)
                    return fail(it, std::strerror(errno));
                continue;
            }
            std::FILE* f = std::fopen(it.path.c_str(), "wb");
            if (!f) return fail(it, std::strerror(errno));
            bool ok = std::fwrite(it.text.data(), 1, it.text.size(), f) == it.text.size();
            ok = (std::fflush(f) == 0) && ok;
            int err = errno;
            ok = (std::fclose(f) == 0) && ok;
            if (!ok) return fail(it, std::strerror(err ? err : errno));
        }
        for (Item& it : items_) {  // the renames
            if (it.tmp.empty()) continue;
            if (std::rename(it.tmp.c_str(), it.path.c_str()) != 0) return fail(it, std::strerror(errno));
            it.tmp.clear();
        }
        return 0;
    }

private:
    struct Item {
        std::string path, text, tmp;
        bool direct = false, changed = true;
    };
    std::vector<Item> items_;

    int fail(const Item& it, const char* why) {
        std::fprintf(stderr, "iqc: error: cannot write '%s': %s\n", it.path.empty() || it.path == "-" ? "standard output" : it.path.c_str(),
                     why);
        for (Item& other : items_)
            if (!other.tmp.empty()) {
                std::remove(other.tmp.c_str());
                other.tmp.clear();
            }
        return 1;
    }
};

// A path as a Makefile rule names it: space, '#', ':' and '\\' before them escaped with '\\', '$' doubled
// (what GNU Make and Ninja both read). A path with a control character (a newline would start a rule or a
// recipe of its own) cannot be written: false.
bool make_escape(const std::string& path, std::string& out) {
    out.clear();
    for (char c : path) {
        // '%' would make the rule a pattern rule for GNU Make, with no escape Ninja reads too.
        if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f || c == '%') return false;
        if (c == ' ' || c == '#' || c == ':' || c == '\\') out += '\\';
        if (c == '$') out += '$';
        out += c;
    }
    return true;
}

// The depfile of one compile: a Makefile rule `OUTPUTS: DEPENDENCIES` naming every file the compile read from
// disk (the scene or document, included and looked-up module files), as absolute paths. False, with `bad` the
// offending path, when a path cannot be written in Makefile syntax.
bool depfile_text(const std::vector<std::string>& outputs, const std::vector<std::string>& deps, std::string& text,
                  std::string& bad) {
    auto abs = [](const std::string& p) {
        std::error_code ec;
        std::filesystem::path a = std::filesystem::absolute(p, ec);
        return ec ? p : a.lexically_normal().string();
    };
    text.clear();
    std::string e;
    for (const auto& o : outputs) {
        if (!make_escape(abs(o), e)) return bad = o, false;
        text += (text.empty() ? "" : " ") + e;
    }
    text += ":";
    for (const auto& d : deps) {
        if (!make_escape(abs(d), e)) return bad = d, false;
        text += " \\\n  " + e;
    }
    text += "\n";
    return true;
}

// A path for a message: control characters as \n, \t or \xNN.
std::string printable(const std::string& s) { return iqc::escape_controls(s); }

}  // namespace

static int run(int argc, char** argv) {
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
    app.require_subcommand(0, 1);
    std::string input, output, target = "shadertoy", dump_ir_spec, inject_fault;
    bool time = false;
    app.add_option("input", input, "scene (.iq), document (.md) or shape module (.iql); with --target wgsl also a Shadertoy "
                                   "shader (.frag, .glsl: mainImage), translated as it is");
    // A file name given empty (`-o "$OUT"` with OUT unset) is a usage error: it wrote to standard output as if
    // -o were left out (a new user's trial).
    const CLI::Validator file_name(
        [](std::string& s) { return s.empty() ? std::string("an empty file name (leave the option out, or write - for standard output)") : std::string(); },
        "FILE");
    app.add_option("-o,--output", output, "where to write the shader (default: standard output; - too)")->check(file_name);
    app.add_option("--target", target,
                   "output kind: shadertoy (default: mainImage, parameters as constants), webgl2 (GLSL ES 3.00 with a "
                   "uniform per parameter), glsl330 (desktop core profile, uniforms), html (one offline page: the webgl2 "
                   "shader on a canvas with a slider per parameter component, reset, play/pause, mouse orbit), cpp (a C++17 "
                   "header: the webgl2 shader as a constant and a constexpr table of its parameters), spirv (a SPIR-V "
                   "binary for Vulkan, needs -o: Vulkan GLSL 4.50 compiled by glslang and validated by SPIRV-Tools; "
                   "inputs, camera and parameters in std140 uniform blocks at set 0, layout in --meta), hlsl (Shader Model "
                   "5.0, cross-compiled from that SPIR-V by SPIRV-Cross and re-checked by glslang), wgsl (WebGPU: that SPIR-V "
                   "translated to WGSL, entry points vs_main and fs_main, the same blocks at @group(0)), threejs (an ES module: "
                   "createMesh(camera) gives a three.js mesh that raymarches the scene through a PerspectiveCamera and "
                   "writes depth, so it and other meshes occlude each other). Every target but shadertoy takes the "
                   "camera as uniforms and writes depth (docs/engines.md)")
        ->check(CLI::IsMember({"shadertoy", "webgl2", "glsl330", "html", "cpp", "spirv", "hlsl", "wgsl", "threejs"}));
    std::string meta;
    app.add_option("--meta", meta, "also write a JSON description of every parameter (instance, module, role, "
                                   "uniform or constant name, type, bounds, default, description)")->check(file_name);
    std::string depfile;
    app.add_option("--depfile", depfile,
                   "also write a Makefile-syntax depfile: the outputs, then every file the compile read (the scene, "
                   "included and looked-up modules), for Ninja's and Make's rebuilds (CMake: iqc_add_shader)")->check(file_name);
    bool quiet = false;
    app.add_flag("-q,--quiet", quiet, "print only diagnostics (no 'wrote' lines); outputs whose bytes did not change are "
                                      "never rewritten, quiet or not");
    std::string passes_list;
    for (const auto& p : iqc::ir::pipeline_passes()) passes_list += fmt::format("{}{} ({})", passes_list.empty() ? "" : ", ", p.name, p.summary);
    CLI::Option* dump_ir_opt =
        app.add_option("--dump-ir", dump_ir_spec,
                       "print the IR to standard error: after the last pass, or with =after-PASS after that pass (=after-lower: "
                       "before the first). Passes, in order: " + passes_list)
            ->expected(0, 1);
    app.add_option("--inject-fault", inject_fault, "testing the internal-error path: fail in this pass, or 'glslang', or 'wgsl'")
        ->group("");
    bool verify_ir = false;
    app.add_flag("--verify-ir", verify_ir, "verify the IR before and after every pass (a fault is an internal error naming the pass)");
    app.add_flag("--time", time, "print the compile time to standard error");
    bool time_passes = false;
    bool strict_ranges = false;
    app.add_flag("--strict-ranges", strict_ranges,
                 "treat range-analysis warnings (a slider can push an operation out of its domain, e.g. a division by "
                 "a value that can be 0), and parameter values outside their slider bounds, as errors");
    int repeat = 0;
    app.add_option("--repeat", repeat,
                   "benchmark: compile N more times in this process and print the median time (the first compile "
                   "pays glslang's one-time set-up)")
        ->check(CLI::Range(1, 100000));
    app.add_flag("--time-passes", time_passes, "print the time of each compiler phase to standard error");

    CLI::App* render = app.add_subcommand("render", "render the scene headlessly to a PNG (no GPU or display needed)");
    std::string r_input, r_output, r_size = "640x360", r_target = "shadertoy";
    float r_time = 0, r_fps = 30;
    int r_frames = 1;
    bool r_stats = false;
    render->add_option("input", r_input, "scene (.iq), document (.md) or shape module (.iql); or a Shadertoy shader (.frag, .glsl: "
                                         "mainImage, as pasted into Shadertoy) to render as it is, e.g. one written by hand")
        ->required();
    render->add_option("-o,--output", r_output, "the PNG to write (with --frames: numbered, out_0000.png, ...)")->required()->check(file_name);
    render->add_option("--size", r_size, "image size WxH (default 640x360; at most 4096x4096)");
    render->add_option("--time", r_time, "iTime in seconds (default 0)");
    render->add_option("--frames", r_frames, "render an animation of N frames")->check(CLI::Range(1, 100000));
    render->add_option("--fps", r_fps, "frames per second of the animation (default 30)")
        ->check(CLI::Validator(
            [](std::string& v) {
                char* end = nullptr;
                double x = std::strtod(v.c_str(), &end);
                return end != v.c_str() && *end == 0 && x > 0 && x <= 1e6 ? std::string() : "must be a number of frames per second in (0, 1e6]";
            },
            "FPS"));
    render->add_option("--target", r_target, "which shader to run: shadertoy (default) or webgl2 (its uniforms at their defaults)")
        ->check(CLI::IsMember({"shadertoy", "webgl2"}));
    render->add_flag("-q,--quiet", quiet, "print only diagnostics and --stats (no 'rendered' line)");
    render->add_flag("--stats", r_stats, "print nan_pixels (colour NaN or ∞), nan_distance_pixels (pixels whose rays met a NaN or ∞ scene distance), steps_mean, steps_p99, evals_mean, evals_p99, shape_evals_mean (shapes evaluated per pixel: a `bound` sphere or a skipped node of a bounding-volume hierarchy stands in for its shapes), shape_evals_per_eval, segment_bounds_mean (segment tracing's bounds evaluated per pixel, each an interval evaluation of every instance's distance or gradient: not counted in evals), frame_ms, renderer");
    CLI::App* bench = app.add_subcommand(
        "bench", "measure what accuracy costs in time on this scene: every march method × hit tolerance × step cap × "
                 "normal method, I♥IQ's one-march-per-instance architecture, and the oracle: the fewest evaluations any march "
                 "certified by overlapping unbounding spheres (sphere tracing, relaxed, auto) can take, against a reference");
    std::string b_input, b_size = "160x90", b_csv, b_plot;
    int b_frames = 5;
    bench->add_option("input", b_input, "scene (.iq), document (.md) or shape module (.iql)")->required();
    bench->add_option("--size", b_size, "image size WxH (default 160x90; at most 1920x1080 pixels)");
    bench->add_option("--csv", b_csv, "write the results as CSV")->check(file_name);
    bench->add_option("--plot", b_plot, "write an SVG plot of scene evaluations per pixel against depth error (log axes, the "
                                        "Pareto front and its settings named)")->check(file_name);
    std::string b_replot;
    bench->add_option("--replot", b_replot, "plot the results of an earlier --csv instead of measuring (with --plot)");
    bench->add_option("--frames", b_frames, "timed frames per setting, after a warm-up (default 5)")->check(CLI::Range(1, 1000));
    CLI::App* serve = app.add_subcommand(
        "serve", "serve the scene's interactive page on 127.0.0.1 only; recompile when the scene or a module it reads "
                 "changes (the page reloads and keeps its slider values); errors are shown in the page");
    std::string s_input;
    int s_port = 8080;
    double s_poll = 0.2;
    serve->add_option("input", s_input, "scene (.iq), document (.md) or shape module (.iql)")->required();
    serve->add_option("--port", s_port, "TCP port on 127.0.0.1 (default 8080; 0 picks a free one)")->check(CLI::Range(0, 65535));
    serve->add_option("--poll", s_poll, "seconds between checks for changed files (default 0.2)")->check(CLI::Range(0.01, 10.0));
    CLI::App* eval = app.add_subcommand(
        "eval", "evaluate a module in double precision and print every output (a graphing calculator)");
    std::string e_input, e_module;
    std::vector<std::string> e_sets;
    eval->add_option("input", e_input, "module file (.iql), or a document/scene with --module")->required();
    eval->add_option("--set", e_sets, "NAME=VALUE: a parameter's value, e.g. p=(2,0,0), r=0.5, A=[1 2; 3 4] "
                                      "(NAME without backticks; unset parameters take their defaults)");
    eval->add_option("--module", e_module, "which module of a .md/.iq file to evaluate");
    double e_time = 0;
    std::vector<double> e_mouse;
    eval->add_option("--time", e_time, "the value of the reserved name `time` (seconds, default 0)");
    bool e_time_passes = false;
    eval->add_flag("--time-passes", e_time_passes, "print the time of each phase to standard error");
    eval->add_option("--mouse", e_mouse, "the value of `mouse` (two numbers in [0,1], default 0 0)")->expected(2);
    eval->add_option("--inject-fault", inject_fault, "testing the internal-error path: fail in this pass")->group("");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        int code = app.exit(e);
        return e.get_exit_code() == 0 ? 0 : (code == 0 ? 0 : 2);
    }
    if (eval->parsed()) {
        iqc::SourceManager sm;
        iqc::Diagnostics diags(sm);
        iqc::EvalRequest req;
        req.inject_fault = inject_fault;
        req.path = e_input;
        req.module = e_module;
        // As render checks --time: a value the shader could not be given is refused, not evaluated into NaN.
        if (!std::isfinite(e_time) || std::fabs(e_time) > 3.4e38) {
            std::fprintf(stderr, "iqc: error: --time must be a finite number of seconds (within 32-bit floats)\n");
            return 2;
        }
        for (double m : e_mouse)
            if (!(m >= 0 && m <= 1)) {
                std::fprintf(stderr, "iqc: error: --mouse takes two numbers in [0, 1] (the pointer's place in the view), not %g\n", m);
                return 2;
            }
        req.inputs.time = e_time;
        if (e_mouse.size() == 2) {
            req.inputs.mouse[0] = e_mouse[0];
            req.inputs.mouse[1] = e_mouse[1];
        }
        for (const auto& s : e_sets) {
            size_t eq = s.find('=');
            if (eq == std::string::npos || eq == 0) {
                std::fprintf(stderr, "iqc: error: --set needs NAME=VALUE, not '%s'\n", s.c_str());
                return 2;
            }
            std::string n = s.substr(0, eq);
            if (n.size() >= 2 && n.front() == '`' && n.back() == '`') n = n.substr(1, n.size() - 2);
            req.sets.push_back({n, s.substr(eq + 1)});
        }
        std::vector<iqc::EvalOutput> outs;
        std::vector<std::pair<std::string, double>> timings;
        if (e_time_passes) req.timings = &timings;
        bool ok = false;
        try {
            ok = iqc::evaluate_module_file(req, sm, diags, outs);
        } catch (const iqc::InternalError& e) {
            std::fputs(diags.render().c_str(), stderr);
            std::fprintf(stderr, "iqc: %s\n", iqc::internal_error_message(e.what()).c_str());
            return 3;
        }
        for (auto& [name, ms] : timings) std::fprintf(stderr, "iqc: %-28s %8.3f ms\n", name.c_str(), ms);
        std::string text = diags.render();
        put(stderr, text);
        if (!ok) return 1;
        for (const auto& o : outs) put(stdout, o.name + " = " + iqc::ir::format_value(o.value) + "\n");
        return 0;
    }
    if (serve->parsed()) return iqc::serve(s_input, s_port, s_poll);
    if (bench->parsed()) {
        // Before any measuring: no output may be a file the bench reads (the scene, what it includes, the CSV
        // being replotted) or the other output (--replot --plot onto the scene turned it into an SVG; --csv and
        // --plot onto one file ran the whole bench first; a new user's trial). The files are the scene's compile's.
        std::vector<std::string> read = {b_input};
        {
            iqc::SourceManager sm;
            iqc::Diagnostics quiet(sm);
            iqc::compile_file(b_input, sm, quiet, iqc::CompileOptions{});
            for (const auto& f : sm.disk_files()) read.push_back(f);
        }
        if (!b_replot.empty()) read.push_back(b_replot);
        if (overwrites_input("--csv", b_csv, read) || overwrites_input("--plot", b_plot, read)) return 2;
        if (!b_csv.empty() && !b_plot.empty() && b_csv != "-" && b_plot != "-") {
            namespace fs = std::filesystem;
            std::error_code e1, e2;
            if (fs::weakly_canonical(b_csv, e1) == fs::weakly_canonical(b_plot, e2) && !e1 && !e2) {
                std::fprintf(stderr, "iqc: error: --csv and --plot are the same file '%s'\n", printable(b_csv).c_str());
                return 2;
            }
        }
    }
    if (bench->parsed() && !b_replot.empty()) {
        if (b_plot.empty()) {
            std::fprintf(stderr, "iqc: error: --replot needs --plot FILE.svg\n");
            return 2;
        }
        std::ifstream in(b_replot, std::ios::binary);
        if (!in) {
            std::fprintf(stderr, "iqc: error: cannot read '%s'\n", printable(b_replot).c_str());
            return 1;
        }
        std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
        iqc::bench::Report rep;
        std::string err;
        if (!iqc::bench::read_csv(text, rep, &err)) {
            std::fprintf(stderr, "iqc: error: %s: %s\n", printable(b_replot).c_str(), printable(err).c_str());
            return 1;
        }
        OutputSet outs;
        outs.add(b_plot, iqc::bench::svg(rep, b_input));
        return outs.commit() != 0 ? 1 : 0;
    }
    if (bench->parsed()) {
        iqc::bench::Options bo;
        bo.input = b_input;
        bo.frames = b_frames;
        char rest = 0;
        if (std::sscanf(b_size.c_str(), "%dx%d%c", &bo.width, &bo.height, &rest) != 2 || bo.width < 1 || bo.height < 1) {
            std::fprintf(stderr, "iqc: error: --size must look like 160x90\n");
            return 2;
        }
        // Each of the ~120 settings draws the picture several times, and the reference marches 4,000 steps a
        // pixel: at most as many pixels as 1920x1080 (a bench of 5000x5000 ran for hours; 640x360 takes a minute).
        if (bo.width > 4096 || bo.height > 4096 || double(bo.width) * bo.height > 1920.0 * 1080.0) {
            std::fprintf(stderr, "iqc: error: --size %dx%d is too large for bench: at most 1920x1080 pixels (and 4096 a side)\n",
                         bo.width, bo.height);
            return 2;
        }
        bool tty = isatty(2);
        auto t0 = std::chrono::steady_clock::now();
        bo.progress = [&](int done, int total, const std::string& what) {
            if (tty) std::fprintf(stderr, "\r\033[Kiqc bench: [%d/%d] %s", done, total, what.c_str());
            else if (done == total) std::fprintf(stderr, "iqc bench: %d settings measured\n", total);
        };
        iqc::bench::Report rep = iqc::bench::run(bo);
        if (tty) std::fprintf(stderr, "\r\033[K");
        if (!rep.error.empty()) {
            std::fprintf(stderr, "iqc: error: %s\n", rep.error.c_str());
            return 1;
        }
        double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::printf("iqc bench %s at %dx%d on %s (%.1f s)\n", b_input.c_str(), bo.width, bo.height, rep.renderer.c_str(), secs);
        std::printf("geometry reference: %s\ncolour reference: %s\n", rep.geometry_reference.c_str(), rep.colour_reference.c_str());
        for (const auto& line : rep.lipschitz) std::printf("lipschitz: %s\n", line.c_str());
        std::printf("\n");
        std::fputs(iqc::bench::table(rep).c_str(), stdout);
        OutputSet outs;
        if (!b_csv.empty()) outs.add(b_csv, iqc::bench::csv(rep));
        if (!b_plot.empty()) outs.add(b_plot, iqc::bench::svg(rep, b_input));
        if (outs.commit() != 0) return 1;
        return 0;
    }
    if (!render->parsed() && input.empty()) {
        std::fprintf(stderr, "iqc: error: no input file (see iqc --help)\n");
        return 2;
    }
    {
        // No output may be the input or another output (the scene would be overwritten by its shader), and
        // standard output takes one of them (-o - --meta - interleaved the shader and its JSON).
        namespace fs = std::filesystem;
        if (!render->parsed() && (output.empty() || output == "-") && (meta == "-" || depfile == "-")) {
            std::fprintf(stderr, "iqc: error: the shader goes to standard output: give --meta and --depfile a file\n");
            return 2;
        }
        std::vector<std::pair<std::string, std::string>> files;
        if (!render->parsed()) files.push_back({"the input", input});
        if (!output.empty() && output != "-") files.push_back({"-o", output});
        if (!meta.empty()) files.push_back({"--meta", meta});
        if (!depfile.empty()) files.push_back({"--depfile", depfile});
        for (size_t i = 0; i < files.size(); ++i)
            for (size_t j = i + 1; j < files.size(); ++j) {
                std::error_code e1, e2;
                fs::path a = fs::weakly_canonical(files[i].second, e1), b = fs::weakly_canonical(files[j].second, e2);
                bool device = fs::exists(a, e1) && !fs::is_regular_file(a, e1);  // -o /dev/null --meta /dev/null is fine
                if (!e1 && !e2 && a == b && !device) {
                    std::fprintf(stderr, "iqc: error: %s and %s are the same file '%s'\n", files[i].first.c_str(),
                                 files[j].first.c_str(), printable(files[j].second).c_str());
                    return 2;
                }
            }
    }
    if (render->parsed()) {
        // A Shadertoy shader as it is (a hand-written reference beside iqc's): rendered with no compile.
        std::string ext = std::filesystem::path(r_input).extension().string();
        if (ext == ".frag" || ext == ".glsl") {
            if (r_stats || r_target != "shadertoy") {
                std::fprintf(stderr, "iqc: error: a Shadertoy shader (%s) is rendered as it is: --stats and --target need a scene\n",
                             printable(r_input).c_str());
                return 2;
            }
            for (int k = 0; k < std::max(r_frames, 1); ++k)
                if (overwrites_input("-o", frame_path(r_output, k, r_frames), {r_input})) return 2;
            std::string code, err;
            if (!iqc::read_source_file(r_input, 0, code, err)) {
                std::fprintf(stderr, "iqc: error: cannot read '%s': %s\n", printable(r_input).c_str(), err.c_str());
                return 1;
            }
            // Tried in a child first: a crash in the driver's compiler is a diagnostic (crash_in_child).
            if (std::string how = crash_in_child([&] {
                    std::string e;
                    auto r = iqc::render::Renderer::create(&e);
                    if (!r) return;
                    iqc::render::RenderOptions one;
                    one.width = one.height = 1;
                    r->render(iqc::glsl::wrap_shadertoy("#line 1\n" + code), one);
                });
                !how.empty())
                return report_compiler_crash(r_input, "the GL driver", how);
            // The driver's messages count the file's own lines.
            return render_command("#line 1\n" + code, iqc::ShaderInputs{}, false, r_output, r_size, r_time, r_frames, r_fps, false, quiet,
                                  [] { return iqc::CompileResult{}; }, r_input, &code);
        }
    }
    auto report = [&](const std::string& path, bool changed) {
        if (!quiet && !path.empty() && path != "-")
            std::fprintf(stderr, changed ? "iqc: wrote %s\n" : "iqc: %s is unchanged\n", path.c_str());
    };
    if (!render->parsed()) {
        // A Shadertoy shader (a .frag a user pasted into shadertoy.com): translated to WGSL as it is.
        std::string ext = std::filesystem::path(input).extension().string();
        if (ext == ".frag" || ext == ".glsl") {
            if (target != "wgsl") {
                std::fprintf(stderr, "iqc: error: a Shadertoy shader (%s) is translated only with --target wgsl, or drawn "
                                     "with `iqc render`; the other targets need a scene (.iq, .md, .iql)\n",
                             printable(input).c_str());
                return 2;
            }
            if (!depfile.empty()) {
                std::fprintf(stderr, "iqc: error: --depfile needs a scene\n");
                return 2;
            }
            std::string code, err;
            if (!iqc::read_source_file(input, 0, code, err)) {
                std::fprintf(stderr, "iqc: error: cannot read '%s': %s\n", printable(input).c_str(), err.c_str());
                return 1;
            }
            if (std::string how = crash_in_child([&] { iqc::glsl::shadertoy_to_wgsl(code); }); !how.empty())
                return report_compiler_crash(input, "glslang", how);
            iqc::glsl::ShadertoyWgsl w = iqc::glsl::shadertoy_to_wgsl(code);
            if (w.user_error) {
                // glslang's "ERROR: iqc:LINE: message" lines, as FILE:LINE:COL: error: message, the line and a caret
                iqc::SourceManager sm;
                iqc::Diagnostics diags(sm);
                iqc::FileId f = sm.add(input, code);
                if (iqc::glsl::locate_shader_log(w.log, f, diags) > 0) put(stderr, diags.render());
                else put(stderr, "iqc: error: glslang rejected " + input + ":\n" + w.log);
                if (code.find("iChannel") != std::string::npos)
                    std::fprintf(stderr, "iqc: note: Shadertoy's iChannel textures are not declared in the WGSL translation\n");
                return 1;
            }
            if (!w.ok) {
                put(stderr, "iqc: internal compiler error: the shader's SPIR-V could not be translated to WGSL (this is a bug "
                            "in iqc; nothing was written):\n" + w.log + "\n");
                return 3;
            }
            std::string name = std::filesystem::path(input).filename().string();
            std::string text = "// " + iqc::glsl::comment_text(name) + ": a Shadertoy shader translated to WGSL by iqc " IQC_VERSION
                               " (Vulkan GLSL, SPIR-V, WGSL).\n// Entry points: vs_main (a full-screen triangle, 3 vertices) "
                               "and fs_main. Inputs: " + w.inputs_block + " (@group(0) @binding(0), std140: iResolution 0, iTime 12, "
                               "iTimeDelta 16, iFrameRate 20, iFrame 24, iMouse 32, iDate 48; 64 bytes).\n" + w.text;
            nlohmann::ordered_json j;
            j["title"] = name;
            j["target"] = "wgsl";
            nlohmann::ordered_json members = nlohmann::ordered_json::array();
            for (const auto& in : iqc::glsl::kShadertoyInputs)
                members.push_back({{"name", in.name}, {"type", in.type}, {"offset", in.offset}});
            j["inputs_block"] = {{"name", w.inputs_block}, {"set", 0}, {"binding", 0},
                                 {"bytes", iqc::glsl::kShadertoyInputsBytes}, {"members", members}};
            j["blocks"] = nlohmann::ordered_json::array();
            j["texture"] = nullptr;
            OutputSet outs;
            size_t shader_out = outs.add(output, text);
            size_t meta_out = meta.empty() ? 0 : outs.add(meta, j.dump(2) + "\n");
            int rc = outs.commit();
            if (rc == 0) {
                if (!meta.empty()) report(meta, outs.changed(meta_out));
                report(output, outs.changed(shader_out));
            }
            return rc;
        }
    }
    if (!depfile.empty() && (render->parsed() || output.empty() || output == "-")) {
        std::fprintf(stderr, "iqc: error: --depfile needs an output file (-o FILE) to name in its rule\n");
        return 2;
    }
    auto t0 = std::chrono::steady_clock::now();
    iqc::SourceManager sm;
    iqc::Diagnostics diags(sm);
    bool dump_ir = dump_ir_opt->count() > 0;
    iqc::CompileOptions opts;
    opts.dump_ir = dump_ir;
    if (!dump_ir_spec.empty()) {
        std::string pass = dump_ir_spec.rfind("after-", 0) == 0 ? dump_ir_spec.substr(6) : "";
        if (!iqc::ir::is_pass_name(pass)) {
            std::fprintf(stderr, "iqc: error: --dump-ir takes after-PASS with PASS one of lower, %s (not '%s')\n",
                         [] { std::string n; for (const auto& p : iqc::ir::pipeline_passes()) n += std::string(n.empty() ? "" : ", ") + p.name; return n; }().c_str(),
                         dump_ir_spec.c_str());
            return 2;
        }
        opts.dump_after = pass;
    }
    opts.inject_fault = inject_fault;
    if (verify_ir) opts.verify_each = true;
    opts.strict_ranges = strict_ranges;
    opts.target = target == "webgl2" || target == "html" || target == "cpp" ? iqc::Target::WebGL2
                  : target == "glsl330"                                      ? iqc::Target::GLSL330
                  : target == "spirv"                                        ? iqc::Target::SPIRV
                  : target == "hlsl"                                         ? iqc::Target::HLSL
                  : target == "wgsl"                                         ? iqc::Target::WGSL
                  : target == "threejs"                                      ? iqc::Target::ThreeJS
                                                                             : iqc::Target::Shadertoy;
    if (target == "spirv" && !render->parsed() && (output.empty() || output == "-")) {
        std::fprintf(stderr, "iqc: error: --target spirv writes a binary SPIR-V module: give the file with -o (e.g. -o scene.spv)\n");
        return 2;
    }
    if (render->parsed()) opts.target = r_target == "webgl2" ? iqc::Target::WebGL2 : iqc::Target::Shadertoy;
    iqc::CompileResult r = iqc::compile_file(render->parsed() ? r_input : input, sm, diags, opts);
    std::string rendered = diags.render();
    put(stderr, rendered);
    if (dump_ir) put(stderr, r.ir);
    if (time_passes)
        for (auto& [name, ms] : r.pass_ms) std::fprintf(stderr, "iqc: %-28s %8.3f ms\n", name.c_str(), ms);
    if (r.exit_code == 3) {
        put(stderr, r.internal + "\n");
        return 3;
    }
    if (r.exit_code != 0) {
        if (diags.error_count() > 1) std::fprintf(stderr, "%zu errors\n", diags.error_count());
        return 1;
    }
    {
        std::vector<std::string> read = sm.disk_files();
        if (render->parsed()) {
            for (int k = 0; k < std::max(r_frames, 1); ++k)
                if (overwrites_input("-o", frame_path(r_output, k, r_frames), read)) return 2;
        } else if (overwrites_input("-o", output, read) || overwrites_input("--meta", meta, read) ||
                   overwrites_input("--depfile", depfile, read)) {
            return 2;
        }
    }
    if (render->parsed()) return render_command(r.code, r.inputs, opts.target != iqc::Target::Shadertoy, r_output, r_size, r_time, r_frames, r_fps, r_stats, quiet,
                                                [&]() {
                                                    iqc::SourceManager sm2;
                                                    iqc::Diagnostics d2(sm2);
                                                    iqc::CompileOptions o2 = opts;
                                                    o2.instrument = true;
                                                    return iqc::compile_file(r_input, sm2, d2, o2);
                                                });
    if (repeat > 0) {
        std::vector<double> times;
        for (int i = 0; i < repeat; ++i) {
            auto s0 = std::chrono::steady_clock::now();
            iqc::SourceManager sm2;
            iqc::Diagnostics d2(sm2);
            iqc::CompileResult r2 = iqc::compile_file(input, sm2, d2, opts);
            times.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - s0).count());
            if (r2.code != r.code) {
                std::fprintf(stderr, "iqc: internal error: output differs between runs\n");
                return 3;
            }
        }
        std::sort(times.begin(), times.end());
        std::fprintf(stderr, "iqc: %d warm compiles: median %.3f ms, min %.3f ms, max %.3f ms (first, cold: %.3f ms)\n",
                     repeat, times[times.size() / 2], times.front(), times.back(),
                     std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() -
                         [&] { double s = 0; for (double x : times) s += x; return s; }());
    }
    if (target == "html" && !render->parsed()) r.code = iqc::html_page(r.code, r.meta);
    if (target == "cpp" && !render->parsed())
        r.code = iqc::cpp_header(r.code, r.meta, std::filesystem::path(input).stem().string());
    if (target == "threejs" && !render->parsed()) {
        try {
            r.code = iqc::three_module(r.code, r.meta, std::filesystem::path(input).filename().string());
        } catch (const iqc::ThreeUnsupported& e) {
            put(stderr, "iqc: error: " + e.message + "\n");
            return 1;
        }
    }
    if (target == "spirv" && !render->parsed()) {  // the module's words, little-endian as SPIR-V files are
        r.code.clear();
        for (uint32_t w : r.spirv)
            for (int b = 0; b < 4; ++b) r.code.push_back(char((w >> (8 * b)) & 0xFF));
    }
    // The depfile's text first: a path it cannot express stops the compile before any output is written.
    std::string dep_text;
    if (!depfile.empty()) {
        std::vector<std::string> outs{output};
        if (!meta.empty()) outs.push_back(meta);
        std::string bad;
        if (!depfile_text(outs, sm.disk_files(), dep_text, bad)) {
            std::fprintf(stderr, "iqc: error: cannot write the depfile '%s': the path '%s' has a control character "
                                 "or '%%' (a newline would start a rule of its own, '%%' a pattern rule), which Makefile syntax "
                                 "cannot express\n",
                         printable(depfile).c_str(), printable(bad).c_str());
            return 1;
        }
    }
    OutputSet outs;
    size_t shader_out = outs.add(output, r.code);
    size_t meta_out = meta.empty() ? 0 : outs.add(meta, r.meta);
    if (!depfile.empty()) outs.add(depfile, dep_text);
    int rc = outs.commit();
    if (time) {
        double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        std::fprintf(stderr, "iqc: compiled in %.2f ms\n", ms);
    }
    if (rc == 0) {
        if (!meta.empty()) report(meta, outs.changed(meta_out));
        report(output, outs.changed(shader_out));
    }
    return rc;
}

// No exception reaches the C++ runtime: anything thrown is a bug in iqc (bad input is a diagnostic), and
// says so with exit code 3.
int main(int argc, char** argv) {
    tune_allocator();
    try {
        int rc = run(argc, argv);
        // What went to standard output (a shader, eval's values, stats, tables) must have arrived: a full disk
        // or a closed pipe is an error, not a silent truncation.
        if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
            std::fprintf(stderr, "iqc: error: cannot write standard output: %s\n", std::strerror(errno));
            return rc == 0 ? 1 : rc;
        }
        return rc;
    } catch (const std::bad_alloc&) {
        std::fprintf(stderr, "iqc: internal compiler error: out of memory (this is a bug in iqc: input should be "
                             "refused with a diagnostic before that)\n");
    } catch (const std::exception& e) {
        put(stderr, std::string("iqc: internal compiler error: ") + e.what() + " (this is a bug in iqc)\n");
    } catch (...) {
        std::fprintf(stderr, "iqc: internal compiler error: unknown exception (this is a bug in iqc)\n");
    }
    return 3;
}
