// Headless rendering of Shadertoy-style fragment shaders.
//
// A Renderer owns one EGL display + OpenGL ES 3 context with no window, no surface and no display
// server (EGL_MESA_platform_surfaceless on Mesa's llvmpipe, or an EGL device on a GPU). It draws a
// full-screen triangle into an offscreen floating-point framebuffer, sets the Shadertoy uniforms and
// reads the result back as float RGBA. Failures (no EGL, shader compile errors, ...) are reported in
// RenderResult::error; nothing here aborts.
//
// Typical use:
//     iqc::render::RenderOptions opts;  opts.width = 640;  opts.height = 360;  opts.time = 1.0f;
//     auto r = iqc::render::render_shadertoy(user_code_with_mainImage, opts);
//     if (!r.ok) report(r.error); else use(r.image);
//
// To render many frames or many shaders, create one Renderer and call render() repeatedly with
// complete `#version 300 es` fragment shaders (e.g. from iqc::glsl::wrap_shadertoy).
//
// Threading: a Renderer makes its context current on the calling thread for the duration of each
// render() and releases it afterwards, so it may be used from any thread, but by one thread at a time.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace iqc::render {

// A float RGBA image, row-major, TOP row first (like a PNG), 4 floats per pixel.
// Note Shadertoy's fragCoord has y = 0 at the BOTTOM row, so fragCoord.y = height - 1 - y + 0.5.
struct Image {
    int width = 0, height = 0;
    std::vector<float> rgba;

    // The 4 floats of pixel (x, y); y = 0 is the top row. No bounds checking beyond an assert.
    const float* pixel(int x, int y) const;
    float* pixel(int x, int y);
};

struct RenderOptions {
    int width = 320, height = 180;
    float time = 0;                     // iTime, seconds
    float mouse[4] = {0, 0, 0, 0};      // iMouse (Shadertoy: xy = current/last drag position, zw = click)
    int frame = 0;                      // iFrame
    // Extra uniforms (a webgl2-target shader's parameters): name -> components (1..16 floats; 9 and 16
    // are mat3 and mat4). Unknown names are ignored.
    std::vector<std::pair<std::string, std::vector<float>>> uniforms;
    std::vector<std::pair<std::string, int>> int_uniforms;
    // Uniform blocks: name, binding point and std140 contents (per-instance data of a webgl2 shader).
    struct UniformBlock {
        std::string name;
        int binding = 0;
        std::vector<unsigned char> bytes;
    };
    std::vector<UniformBlock> uniform_blocks;
    // A data texture read with texelFetch (RGBA32F, width·height texels); bound to unit 4. Empty name: none.
    struct DataTexture {
        std::string name;
        int width = 0, height = 0;
        std::vector<float> rgba;
    } data_texture;
    // Draw in horizontal bands of this many rows (0: one draw), reporting progress after each band —
    // long renders then show progress, and drivers with watchdogs get short draws.
    int band_rows = 0;
    // Draw the frame this many more times after the first and report each draw's time (benchmarks: the
    // first draw includes the driver's lazy compilation).
    int repeat = 0;
    std::function<void(int rows_done, int rows_total)> progress;
};

struct RenderResult {
    bool ok = false;
    std::string error;                  // why ok == false (includes the GL info log for compile errors)
    Image image;                        // valid when ok
    std::string renderer;               // GL_RENDERER string (plus a note if the framebuffer is not float)
    double compile_ms = 0;              // compile + link of the shader program
    double frame_ms = 0;                // draw + glFinish
    std::vector<double> repeat_ms;      // the repeated draws' times (RenderOptions::repeat)
};

// An EGL/GLES 3 context able to render full-screen fragment shaders offscreen.
class Renderer {
public:
    // Creates the headless context. Returns nullptr (and sets *error when error != nullptr) if EGL or
    // an OpenGL ES 3 context is unavailable.
    //
    // EGL platforms are tried in this order: surfaceless Mesa, the first EGL device, the default
    // display. The environment variable IQC_EGL_PLATFORM = "surfaceless" | "device" | "default"
    // restricts the search to one of them (useful on machines where Mesa's surfaceless platform would
    // shadow a GPU's device platform).
    static std::unique_ptr<Renderer> create(std::string* error);

    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    // GL_RENDERER (e.g. "llvmpipe (LLVM 15.0.6, 256 bits)"), plus a note when the framebuffer format
    // had to fall back from RGBA32F.
    std::string renderer_name() const;

    // Which EGL platform was used: "surfaceless", "device" or "default".
    std::string platform_name() const;

    // Renders one frame of a complete `#version 300 es` fragment shader that declares the Shadertoy
    // uniforms it uses (any subset; missing ones are skipped) and writes its colour output.
    RenderResult render(const std::string& full_fragment_source_es300, const RenderOptions& opts);

    struct State;  // EGL/GL handles; defined in Render.cpp

private:
    explicit Renderer(std::unique_ptr<State> state);
    std::unique_ptr<State> state_;
};

// Renders one frame of a Shadertoy shader (the user's code, containing mainImage) headlessly.
// Reuses one process-wide Renderer (created on first use; if creation fails the error is returned and
// creation is retried on the next call). Thread-safe: concurrent calls are serialised by a mutex.
RenderResult render_shadertoy(const std::string& user_code, const RenderOptions& opts);

}  // namespace iqc::render
