// Headless EGL + OpenGL ES 3 renderer for Shadertoy-style fragment shaders (see Render.h).
//
// Setup (Renderer::create):
//   1. Find an EGL display that needs no window system: EGL_PLATFORM_SURFACELESS_MESA, then the EGL
//      devices from eglQueryDevicesEXT (EGL_PLATFORM_DEVICE_EXT), then eglGetDisplay(EGL_DEFAULT_DISPLAY).
//   2. Create an OpenGL ES 3.2 (else 3.0) context and make it current with no surface
//      (EGL_KHR_surfaceless_context); if the display cannot do that, a 1x1 pbuffer is used instead.
//   3. Probe which colour format is renderable: RGBA32F, then RGBA16F, then RGBA8.
//
// Each render() compiles the program, renders a full-screen triangle into a fresh framebuffer object,
// reads it back as floats, and deletes every GL object it created.
#include "render/Render.h"

#include "glsl/ShadertoyWrapper.h"
#include "source/Sanitizer.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <GLES3/gl3.h>

#include <fmt/format.h>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <string_view>
#include <utility>

namespace iqc::render {

// ---------------------------------------------------------------------------------------------------
// Image
// ---------------------------------------------------------------------------------------------------

const float* Image::pixel(int x, int y) const {
    assert(x >= 0 && x < width && y >= 0 && y < height);
    return rgba.data() + (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * 4;
}

float* Image::pixel(int x, int y) {
    assert(x >= 0 && x < width && y >= 0 && y < height);
    return rgba.data() + (static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)) * 4;
}

namespace {

// ---------------------------------------------------------------------------------------------------
// Small helpers
// ---------------------------------------------------------------------------------------------------

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// True if the space-separated extension list `list` contains `name` exactly.
bool has_extension(const char* list, std::string_view name) {
    if (!list) return false;
    std::string_view s(list);
    size_t pos = 0;
    while (pos < s.size()) {
        size_t end = s.find(' ', pos);
        if (end == std::string_view::npos) end = s.size();
        if (s.substr(pos, end - pos) == name) return true;
        pos = end + 1;
    }
    return false;
}

const char* egl_error_name(EGLint e) {
    switch (e) {
        case EGL_SUCCESS: return "EGL_SUCCESS";
        case EGL_NOT_INITIALIZED: return "EGL_NOT_INITIALIZED";
        case EGL_BAD_ACCESS: return "EGL_BAD_ACCESS";
        case EGL_BAD_ALLOC: return "EGL_BAD_ALLOC";
        case EGL_BAD_ATTRIBUTE: return "EGL_BAD_ATTRIBUTE";
        case EGL_BAD_CONFIG: return "EGL_BAD_CONFIG";
        case EGL_BAD_CONTEXT: return "EGL_BAD_CONTEXT";
        case EGL_BAD_CURRENT_SURFACE: return "EGL_BAD_CURRENT_SURFACE";
        case EGL_BAD_DISPLAY: return "EGL_BAD_DISPLAY";
        case EGL_BAD_MATCH: return "EGL_BAD_MATCH";
        case EGL_BAD_NATIVE_PIXMAP: return "EGL_BAD_NATIVE_PIXMAP";
        case EGL_BAD_NATIVE_WINDOW: return "EGL_BAD_NATIVE_WINDOW";
        case EGL_BAD_PARAMETER: return "EGL_BAD_PARAMETER";
        case EGL_BAD_SURFACE: return "EGL_BAD_SURFACE";
        case EGL_CONTEXT_LOST: return "EGL_CONTEXT_LOST";
        default: return "unknown EGL error";
    }
}

std::string egl_error_string() {
    EGLint e = eglGetError();
    return fmt::format("{} (0x{:04X})", egl_error_name(e), static_cast<unsigned>(e));
}

const char* gl_error_name(GLenum e) {
    switch (e) {
        case GL_NO_ERROR: return "GL_NO_ERROR";
        case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
        case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
        case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
        case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
        case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
        default: return "unknown GL error";
    }
}

// Clears all pending GL errors; returns the first one (GL_NO_ERROR if none).
GLenum drain_gl_errors() {
    GLenum first = GL_NO_ERROR;
    for (int i = 0; i < 32; ++i) {  // bounded: a lost context may report errors forever
        GLenum e = glGetError();
        if (e == GL_NO_ERROR) break;
        if (first == GL_NO_ERROR) first = e;
    }
    return first;
}

// ---------------------------------------------------------------------------------------------------
// EGL display reference counting
//
// EGL displays are process-wide singletons per (platform, native display): two Renderers on the same
// platform get the same EGLDisplay, and eglTerminate would pull it out from under the other one. So
// displays are initialised through acquire_display() and terminated only when the last user releases.
// ---------------------------------------------------------------------------------------------------

std::mutex g_display_mutex;
std::map<EGLDisplay, int> g_display_refs;

bool acquire_display(EGLDisplay dpy, std::string* why) {
    std::lock_guard<std::mutex> lock(g_display_mutex);
    EGLint major = 0, minor = 0;
    if (!eglInitialize(dpy, &major, &minor)) {  // a no-op if already initialised
        *why = "eglInitialize failed: " + egl_error_string();
        return false;
    }
    ++g_display_refs[dpy];
    return true;
}

void release_display(EGLDisplay dpy) {
    std::lock_guard<std::mutex> lock(g_display_mutex);
    auto it = g_display_refs.find(dpy);
    if (it == g_display_refs.end()) return;
    if (--it->second == 0) {
        g_display_refs.erase(it);
        // Sanitizer builds keep the display, and so Mesa's driver, loaded: eglTerminate unloads the driver,
        // whose globals were the only pointers to some of its allocations, and LeakSanitizer then reports
        // those (with no stack: the code is gone) as leaks of the process. They are Mesa's, not iqc's.
        if (!kAddressSanitizerBuild) eglTerminate(dpy);
    }
}

// ---------------------------------------------------------------------------------------------------
// Finding a display
// ---------------------------------------------------------------------------------------------------

struct DisplayCandidate {
    EGLDisplay display = EGL_NO_DISPLAY;
    std::string platform;  // "surfaceless", "device" or "default"
    std::string detail;    // e.g. "device 0 of 2"
};

// eglGetPlatformDisplay (EGL 1.5) or eglGetPlatformDisplayEXT, whichever the library exposes.
EGLDisplay get_platform_display(EGLenum platform, void* native_display) {
    auto ext = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (ext) return ext(platform, native_display, nullptr);
    using CoreFn = EGLDisplay(EGLAPIENTRYP)(EGLenum, void*, const EGLAttrib*);
    auto core = reinterpret_cast<CoreFn>(eglGetProcAddress("eglGetPlatformDisplay"));
    if (core) return core(platform, native_display, nullptr);
    return EGL_NO_DISPLAY;
}

// Lists the displays to try, in order of preference, honouring IQC_EGL_PLATFORM. Displays are obtained
// but not initialised. `log` collects a line per platform that produced nothing.
std::vector<DisplayCandidate> display_candidates(std::string& log) {
    std::string only;
    if (const char* env = std::getenv("IQC_EGL_PLATFORM")) only = env;
    auto wanted = [&](std::string_view p) { return only.empty() || only == p; };

    // Client extensions (EGL_EXT_client_extensions); null if the library has none.
    const char* client_exts = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    eglGetError();  // eglQueryString(EGL_NO_DISPLAY, ...) sets EGL_BAD_DISPLAY on old libraries

    std::vector<DisplayCandidate> out;

    if (wanted("surfaceless")) {
        EGLDisplay d = get_platform_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY);
        if (d != EGL_NO_DISPLAY)
            out.push_back({d, "surfaceless", "EGL_PLATFORM_SURFACELESS_MESA"});
        else
            log += "  surfaceless: no display (" + egl_error_string() + ")\n";
    }

    if (wanted("device")) {
        auto query_devices = reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
        if (!query_devices || !(has_extension(client_exts, "EGL_EXT_device_enumeration") ||
                                has_extension(client_exts, "EGL_EXT_device_base"))) {
            log += "  device: EGL_EXT_device_enumeration not supported\n";
        } else {
            EGLDeviceEXT devices[16];
            EGLint n = 0;
            if (!query_devices(16, devices, &n) || n <= 0) {
                log += "  device: eglQueryDevicesEXT found no devices\n";
            } else {
                for (EGLint i = 0; i < n; ++i) {
                    EGLDisplay d = get_platform_display(EGL_PLATFORM_DEVICE_EXT, devices[i]);
                    if (d != EGL_NO_DISPLAY)
                        out.push_back({d, "device", fmt::format("EGL device {} of {}", i, n)});
                    else
                        log += fmt::format("  device {}: no display ({})\n", i, egl_error_string());
                }
            }
        }
    }

    if (wanted("default")) {
        EGLDisplay d = eglGetDisplay(EGL_DEFAULT_DISPLAY);
        if (d != EGL_NO_DISPLAY)
            out.push_back({d, "default", "eglGetDisplay(EGL_DEFAULT_DISPLAY)"});
        else
            log += "  default: eglGetDisplay returned EGL_NO_DISPLAY\n";
    }

    if (!only.empty() && only != "surfaceless" && only != "device" && only != "default")
        log += "  IQC_EGL_PLATFORM='" + only + "' is not one of surfaceless, device, default\n";
    return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Renderer state
// ---------------------------------------------------------------------------------------------------

struct Renderer::State {
    EGLDisplay display = EGL_NO_DISPLAY;
    EGLContext context = EGL_NO_CONTEXT;
    EGLSurface surface = EGL_NO_SURFACE;  // EGL_NO_SURFACE (surfaceless) or a 1x1 pbuffer fallback
    bool display_acquired = false;

    std::string platform;     // "surfaceless" | "device" | "default"
    std::string gl_renderer;  // GL_RENDERER
    std::string format_note;  // empty when rendering to RGBA32F

    // Colour buffer format chosen by probe_color_format().
    GLenum internal_format = GL_RGBA32F;
    GLenum read_type = GL_FLOAT;  // GL_FLOAT for float formats, GL_UNSIGNED_BYTE for RGBA8

    GLint max_size = 0;  // largest width/height we can render

    // The last program, kept for the next render of the same source (benchmarks render one program many
    // times with other uniforms). Freed with the context.
    std::string cached_source;
    GLuint cached_program = 0;

    bool make_current() { return eglMakeCurrent(display, surface, surface, context) == EGL_TRUE; }
    void release_current() { eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT); }

    ~State() {
        if (display == EGL_NO_DISPLAY) return;
        release_current();
        if (surface != EGL_NO_SURFACE) eglDestroySurface(display, surface);
        if (context != EGL_NO_CONTEXT) eglDestroyContext(display, context);
        if (display_acquired) release_display(display);
    }
};

namespace {

// Creates a GLES 3 context on an initialised display and makes it current. Fills state.context/surface.
bool create_context(Renderer::State& st, std::string* why) {
    EGLDisplay dpy = st.display;
    if (!eglBindAPI(EGL_OPENGL_ES_API)) {
        *why = "eglBindAPI(EGL_OPENGL_ES_API) failed: " + egl_error_string();
        return false;
    }
    const char* exts = eglQueryString(dpy, EGL_EXTENSIONS);
    const bool surfaceless = has_extension(exts, "EGL_KHR_surfaceless_context");

    // A config able to run GLES 3. Prefer one with pbuffer support (needed only for the fallback path),
    // then any surface type, then no config at all (EGL_KHR_no_config_context).
    EGLConfig config = EGL_NO_CONFIG_KHR;
    bool have_config = false;
    for (EGLint surface_type : {EGLint(EGL_PBUFFER_BIT), EGLint(0)}) {
        const EGLint attribs[] = {EGL_RENDERABLE_TYPE, EGL_OPENGL_ES3_BIT, EGL_SURFACE_TYPE, surface_type,
                                  EGL_NONE};
        EGLint n = 0;
        if (eglChooseConfig(dpy, attribs, &config, 1, &n) && n > 0) {
            have_config = true;
            break;
        }
    }
    if (!have_config) {
        if (!has_extension(exts, "EGL_KHR_no_config_context")) {
            *why = "no EGLConfig supports OpenGL ES 3";
            return false;
        }
        config = EGL_NO_CONFIG_KHR;
    }

    // GLES 3.2, then 3.0 (both need EGL 1.5 / EGL_KHR_create_context for the minor version), then plain
    // "client version 3" for old EGLs.
    const EGLint ctx_32[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 2, EGL_NONE};
    const EGLint ctx_30[] = {EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 0, EGL_NONE};
    const EGLint ctx_3[] = {EGL_CONTEXT_CLIENT_VERSION, 3, EGL_NONE};
    std::string ctx_error;
    for (const EGLint* attribs : {ctx_32, ctx_30, ctx_3}) {
        st.context = eglCreateContext(dpy, config, EGL_NO_CONTEXT, attribs);
        if (st.context != EGL_NO_CONTEXT) break;
        ctx_error = egl_error_string();
    }
    if (st.context == EGL_NO_CONTEXT) {
        *why = "eglCreateContext (OpenGL ES 3.x) failed: " + ctx_error;
        return false;
    }

    // Surfaceless first; a 1x1 pbuffer if the display cannot do without a surface.
    if (surfaceless && st.make_current()) return true;
    std::string surfaceless_error = surfaceless ? "eglMakeCurrent without surface failed: " + egl_error_string()
                                                : "EGL_KHR_surfaceless_context not supported";
    if (have_config) {
        const EGLint pb_attribs[] = {EGL_WIDTH, 1, EGL_HEIGHT, 1, EGL_NONE};
        st.surface = eglCreatePbufferSurface(dpy, config, pb_attribs);
        if (st.surface != EGL_NO_SURFACE && st.make_current()) return true;
    }
    *why = surfaceless_error + "; pbuffer fallback failed: " + egl_error_string();
    return false;
}

// Picks the best renderable colour format: RGBA32F, RGBA16F, RGBA8 (tested by FBO completeness).
bool probe_color_format(Renderer::State& st, std::string* why) {
    struct Format { GLenum internal; GLenum read_type; const char* note; };
    const Format formats[] = {
        {GL_RGBA32F, GL_FLOAT, ""},
        {GL_RGBA16F, GL_FLOAT, "RGBA16F framebuffer: RGBA32F not renderable"},
        {GL_RGBA8, GL_UNSIGNED_BYTE, "RGBA8 framebuffer: float formats not renderable, output quantised to 8 bits"},
    };
    drain_gl_errors();
    for (const Format& f : formats) {
        GLuint tex = 0, fbo = 0;
        glGenTextures(1, &tex);
        glBindTexture(GL_TEXTURE_2D, tex);
        glTexStorage2D(GL_TEXTURE_2D, 1, f.internal, 1, 1);
        glGenFramebuffers(1, &fbo);
        glBindFramebuffer(GL_FRAMEBUFFER, fbo);
        glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, tex, 0);
        bool complete = glCheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glBindTexture(GL_TEXTURE_2D, 0);
        glDeleteFramebuffers(1, &fbo);
        glDeleteTextures(1, &tex);
        bool errors = drain_gl_errors() != GL_NO_ERROR;
        if (complete && !errors) {
            st.internal_format = f.internal;
            st.read_type = f.read_type;
            st.format_note = f.note;
            return true;
        }
    }
    *why = "no renderable colour format (RGBA32F, RGBA16F, RGBA8) for framebuffer objects";
    return false;
}

// Fills GL information (renderer string, size limits) and checks the context really is ES >= 3.
bool query_gl(Renderer::State& st, std::string* why) {
    const char* version = reinterpret_cast<const char*>(glGetString(GL_VERSION));
    const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
    GLint major = 0;
    glGetIntegerv(GL_MAJOR_VERSION, &major);  // GL_INVALID_ENUM (major stays 0) on ES 2
    drain_gl_errors();
    if (major < 3) {
        *why = fmt::format("context is not OpenGL ES 3 (GL_VERSION '{}')", version ? version : "?");
        return false;
    }
    st.gl_renderer = renderer ? renderer : "";
    if (st.gl_renderer.empty()) st.gl_renderer = "(unknown GL_RENDERER)";

    GLint tex = 0, rb = 0, vp[2] = {0, 0};
    glGetIntegerv(GL_MAX_TEXTURE_SIZE, &tex);
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &rb);
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, vp);
    st.max_size = std::min({tex, rb, vp[0], vp[1]});
    return true;
}

// Tries one display candidate end to end. On failure the state is cleaned up by its destructor.
std::unique_ptr<Renderer::State> try_display(const DisplayCandidate& cand, std::string* why) {
    auto st = std::make_unique<Renderer::State>();
    st->display = cand.display;
    st->platform = cand.platform;
    if (!acquire_display(cand.display, why)) {
        st->display = EGL_NO_DISPLAY;  // nothing to clean up
        return nullptr;
    }
    st->display_acquired = true;
    if (!create_context(*st, why)) return nullptr;
    if (!query_gl(*st, why)) return nullptr;
    if (!probe_color_format(*st, why)) return nullptr;
    st->release_current();  // render() makes it current on whichever thread calls it
    return st;
}

// The trivial vertex shader: a triangle covering clip space, from gl_VertexID alone (no buffers).
constexpr const char* kVertexShader =
    "#version 300 es\n"
    "void main() {\n"
    "    // vertices (-1,-1), (3,-1), (-1,3): one triangle that covers the whole viewport\n"
    "    vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);\n"
    "    gl_Position = vec4(p, 0.0, 1.0);\n"
    "}\n";

// GL object names created by one render; deleted on scope exit (deleting name 0 is a no-op).
// Must be destroyed while the context is current.
struct GlObjects {
    GLuint vs = 0, fs = 0, program = 0, texture = 0, fbo = 0, vao = 0, data_texture = 0;
    std::vector<GLuint> buffers;  // uniform blocks
    GlObjects() = default;
    GlObjects(const GlObjects&) = delete;
    GlObjects& operator=(const GlObjects&) = delete;
    ~GlObjects() {
        glBindFramebuffer(GL_FRAMEBUFFER, 0);
        glBindVertexArray(0);
        glUseProgram(0);
        glDeleteFramebuffers(1, &fbo);
        glDeleteTextures(1, &texture);
        glDeleteTextures(1, &data_texture);
        if (!buffers.empty()) glDeleteBuffers(GLsizei(buffers.size()), buffers.data());
        glDeleteVertexArrays(1, &vao);
        glDeleteProgram(program);
        glDeleteShader(vs);
        glDeleteShader(fs);
    }
};

std::string shader_log(GLuint shader) {
    GLint len = 0;
    glGetShaderiv(shader, GL_INFO_LOG_LENGTH, &len);
    if (len <= 1) return {};
    std::string log(static_cast<size_t>(len), '\0');
    glGetShaderInfoLog(shader, len, nullptr, log.data());
    log.resize(std::strlen(log.c_str()));
    return log;
}

std::string program_log(GLuint program) {
    GLint len = 0;
    glGetProgramiv(program, GL_INFO_LOG_LENGTH, &len);
    if (len <= 1) return {};
    std::string log(static_cast<size_t>(len), '\0');
    glGetProgramInfoLog(program, len, nullptr, log.data());
    log.resize(std::strlen(log.c_str()));
    return log;
}

// Compiles one shader stage into `out`; on failure returns false and sets *why (with the info log).
bool compile_shader(GLenum stage, const std::string& source, GLuint& out, std::string* why) {
    out = glCreateShader(stage);
    const char* src = source.c_str();
    const GLint len = static_cast<GLint>(source.size());
    glShaderSource(out, 1, &src, &len);
    glCompileShader(out);
    GLint ok = GL_FALSE;
    glGetShaderiv(out, GL_COMPILE_STATUS, &ok);
    if (ok == GL_TRUE) return true;
    const char* what = stage == GL_VERTEX_SHADER ? "vertex" : "fragment";
    *why = fmt::format("{} shader compile failed:\n{}", what, shader_log(out));
    return false;
}

// The texture unit of a shader's data texture (Shadertoy's channels use 0-3).
constexpr int kDataTextureUnit = 4;

// Sets every Shadertoy uniform the program declares (and did not optimise away).
void set_shadertoy_uniforms(GLuint program, const RenderOptions& o) {
    auto loc = [program](const char* name) { return glGetUniformLocation(program, name); };
    const GLfloat zeros[4 * 3] = {};
    GLint l;
    if ((l = loc("iResolution")) != -1) glUniform3f(l, float(o.width), float(o.height), 1.0f);
    if ((l = loc("iTime")) != -1) glUniform1f(l, o.time);
    if ((l = loc("iTimeDelta")) != -1) glUniform1f(l, 1.0f / 60.0f);
    if ((l = loc("iFrameRate")) != -1) glUniform1f(l, 60.0f);
    if ((l = loc("iFrame")) != -1) glUniform1i(l, o.frame);
    if ((l = loc("iMouse")) != -1) glUniform4fv(l, 1, o.mouse);
    if ((l = loc("iDate")) != -1) glUniform4fv(l, 1, zeros);  // deterministic: no wall-clock date
    if ((l = loc("iSampleRate")) != -1) glUniform1f(l, 44100.0f);
    if ((l = loc("iChannelTime")) != -1) glUniform1fv(l, 4, zeros);
    if ((l = loc("iChannelResolution")) != -1) glUniform3fv(l, 4, zeros);
    // No textures are bound: sampling iChannelN reads an incomplete texture, i.e. (0, 0, 0, 1).
    const char* channels[4] = {"iChannel0", "iChannel1", "iChannel2", "iChannel3"};
    for (int i = 0; i < 4; ++i)
        if ((l = loc(channels[i])) != -1) glUniform1i(l, i);
    // A non-Shadertoy shader may declare a name with another type: ignore the resulting GL errors.
    drain_gl_errors();
}

// The body of Renderer::render, with the context current.
RenderResult render_current(Renderer::State& st, const std::string& fs_source, const RenderOptions& o) {
    RenderResult res;
    res.renderer = st.gl_renderer;
    if (!st.format_note.empty()) res.renderer += " [" + st.format_note + "]";

    const int w = o.width, h = o.height;
    if (w <= 0 || h <= 0 || w > st.max_size || h > st.max_size) {
        res.error = fmt::format("invalid image size {}x{} (each side must be 1..{})", w, h, st.max_size);
        return res;
    }

    GlObjects gl;
    drain_gl_errors();

    // Compile and link (or reuse the program of the previous render of the same source).
    const auto t_compile = Clock::now();
    if (st.cached_program && st.cached_source == fs_source) {
        gl.program = st.cached_program;
    } else {
        if (st.cached_program) {
            glDeleteProgram(st.cached_program);
            st.cached_program = 0;
            st.cached_source.clear();
        }
        if (!compile_shader(GL_VERTEX_SHADER, kVertexShader, gl.vs, &res.error)) return res;
        if (!compile_shader(GL_FRAGMENT_SHADER, fs_source, gl.fs, &res.error)) return res;
        gl.program = glCreateProgram();
        glAttachShader(gl.program, gl.vs);
        glAttachShader(gl.program, gl.fs);
        glLinkProgram(gl.program);
        GLint linked = GL_FALSE;
        glGetProgramiv(gl.program, GL_LINK_STATUS, &linked);
        if (linked != GL_TRUE) {
            res.error = "shader program link failed:\n" + program_log(gl.program);
            return res;
        }
        st.cached_program = gl.program;
        st.cached_source = fs_source;
    }
    res.compile_ms = ms_since(t_compile);
    GLuint program = gl.program;
    gl.program = 0;  // owned by the cache now

    // Offscreen colour buffer.
    glGenTextures(1, &gl.texture);
    glBindTexture(GL_TEXTURE_2D, gl.texture);
    glTexStorage2D(GL_TEXTURE_2D, 1, st.internal_format, w, h);
    glBindTexture(GL_TEXTURE_2D, 0);
    glGenFramebuffers(1, &gl.fbo);
    glBindFramebuffer(GL_FRAMEBUFFER, gl.fbo);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, gl.texture, 0);
    const GLenum draw_buffer = GL_COLOR_ATTACHMENT0;
    glDrawBuffers(1, &draw_buffer);
    if (GLenum status = glCheckFramebufferStatus(GL_FRAMEBUFFER); status != GL_FRAMEBUFFER_COMPLETE) {
        GLenum err = drain_gl_errors();
        res.error = fmt::format("framebuffer {}x{} incomplete (status 0x{:04X}, {})", w, h, status, gl_error_name(err));
        return res;
    }

    glUseProgram(program);
    set_shadertoy_uniforms(program, o);
    for (const auto& [name, v] : o.int_uniforms)
        if (GLint l = glGetUniformLocation(program, name.c_str()); l != -1) glUniform1i(l, v);
    // Float uniforms by their declared type (a mat2 and a vec4 both have 4 values; mat3x2 has 6), values in
    // GLSL's order (matrices column by column).
    std::map<std::string, GLenum> types;
    {
        GLint count = 0;
        glGetProgramiv(program, GL_ACTIVE_UNIFORMS, &count);
        char name[512];
        for (GLint i = 0; i < count; ++i) {
            GLsizei len = 0;
            GLint size = 0;
            GLenum type = 0;
            glGetActiveUniform(program, GLuint(i), sizeof name, &len, &size, &type, name);
            types[std::string(name, size_t(len))] = type;
        }
    }
    for (const auto& uniform : o.uniforms) {
        const std::string& name = uniform.first;  // (clang 14 cannot capture a structured binding in a lambda)
        const std::vector<float>& v = uniform.second;
        GLint l = glGetUniformLocation(program, name.c_str());
        if (l == -1 || !types.count(name)) continue;
        const float* d = v.data();
        auto need = [&](size_t n) { return v.size() == n; };
        switch (types[name]) {
            case GL_FLOAT: if (need(1)) glUniform1f(l, d[0]); break;
            case GL_FLOAT_VEC2: if (need(2)) glUniform2fv(l, 1, d); break;
            case GL_FLOAT_VEC3: if (need(3)) glUniform3fv(l, 1, d); break;
            case GL_FLOAT_VEC4: if (need(4)) glUniform4fv(l, 1, d); break;
            case GL_FLOAT_MAT2: if (need(4)) glUniformMatrix2fv(l, 1, GL_FALSE, d); break;
            case GL_FLOAT_MAT3: if (need(9)) glUniformMatrix3fv(l, 1, GL_FALSE, d); break;
            case GL_FLOAT_MAT4: if (need(16)) glUniformMatrix4fv(l, 1, GL_FALSE, d); break;
            case GL_FLOAT_MAT2x3: if (need(6)) glUniformMatrix2x3fv(l, 1, GL_FALSE, d); break;
            case GL_FLOAT_MAT3x2: if (need(6)) glUniformMatrix3x2fv(l, 1, GL_FALSE, d); break;
            case GL_FLOAT_MAT2x4: if (need(8)) glUniformMatrix2x4fv(l, 1, GL_FALSE, d); break;
            case GL_FLOAT_MAT4x2: if (need(8)) glUniformMatrix4x2fv(l, 1, GL_FALSE, d); break;
            case GL_FLOAT_MAT3x4: if (need(12)) glUniformMatrix3x4fv(l, 1, GL_FALSE, d); break;
            case GL_FLOAT_MAT4x3: if (need(12)) glUniformMatrix4x3fv(l, 1, GL_FALSE, d); break;
            default: break;
        }
    }
    // Uniform blocks (std140 bytes) and the data texture (RGBA32F, read with texelFetch) of per-instance data.
    for (const auto& b : o.uniform_blocks) {
        GLuint index = glGetUniformBlockIndex(program, b.name.c_str());
        if (index == GL_INVALID_INDEX) continue;
        glUniformBlockBinding(program, index, GLuint(b.binding));
        GLuint buf = 0;
        glGenBuffers(1, &buf);
        gl.buffers.push_back(buf);
        glBindBuffer(GL_UNIFORM_BUFFER, buf);
        glBufferData(GL_UNIFORM_BUFFER, GLsizeiptr(b.bytes.size()), b.bytes.data(), GL_STATIC_DRAW);
        glBindBufferBase(GL_UNIFORM_BUFFER, GLuint(b.binding), buf);
    }
    if (!o.data_texture.name.empty()) {
        const auto& t = o.data_texture;
        glActiveTexture(GL_TEXTURE0 + kDataTextureUnit);
        glGenTextures(1, &gl.data_texture);
        glBindTexture(GL_TEXTURE_2D, gl.data_texture);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, t.width, t.height, 0, GL_RGBA, GL_FLOAT, t.rgba.data());
        glActiveTexture(GL_TEXTURE0);
        if (GLint l = glGetUniformLocation(program, t.name.c_str()); l != -1) glUniform1i(l, kDataTextureUnit);
    }
    drain_gl_errors();

    // Draw. A tiled renderer (for drivers with watchdogs) would loop here over glScissor rectangles,
    // with a glFinish after each tile.
    glGenVertexArrays(1, &gl.vao);  // no attributes, but ES 3 requires a bound VAO to draw
    glBindVertexArray(gl.vao);
    glViewport(0, 0, w, h);
    glDisable(GL_BLEND);
    glDisable(GL_DEPTH_TEST);
    glDisable(GL_SCISSOR_TEST);
    glDisable(GL_DITHER);
    glClearColor(0, 0, 0, 0);
    glClear(GL_COLOR_BUFFER_BIT);
    const auto t_frame = Clock::now();
    if (o.band_rows <= 0 || o.band_rows >= h) {
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glFinish();
        if (o.progress) o.progress(h, h);
    } else {
        glEnable(GL_SCISSOR_TEST);
        for (int y0 = 0; y0 < h; y0 += o.band_rows) {
            int rows = std::min(o.band_rows, h - y0);
            glScissor(0, h - y0 - rows, w, rows);  // top band first
            glDrawArrays(GL_TRIANGLES, 0, 3);
            glFinish();
            if (o.progress) o.progress(y0 + rows, h);
        }
        glDisable(GL_SCISSOR_TEST);
    }
    res.frame_ms = ms_since(t_frame);
    for (int k = 0; k < o.repeat; ++k) {
        const auto t0 = Clock::now();
        glDrawArrays(GL_TRIANGLES, 0, 3);
        glFinish();
        res.repeat_ms.push_back(ms_since(t0));
    }
    if (GLenum err = drain_gl_errors(); err != GL_NO_ERROR) {
        res.error = fmt::format("draw failed: {}", gl_error_name(err));
        return res;
    }

    // Read back (GL's row 0 is the bottom) and flip so that row 0 is the top.
    const size_t row_floats = static_cast<size_t>(w) * 4;
    std::vector<float> bottom_up(row_floats * static_cast<size_t>(h));
    glReadBuffer(GL_COLOR_ATTACHMENT0);
    glPixelStorei(GL_PACK_ALIGNMENT, 4);
    if (st.read_type == GL_FLOAT) {
        glReadPixels(0, 0, w, h, GL_RGBA, GL_FLOAT, bottom_up.data());
    } else {
        std::vector<unsigned char> bytes(row_floats * static_cast<size_t>(h));
        glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, bytes.data());
        for (size_t i = 0; i < bytes.size(); ++i) bottom_up[i] = bytes[i] / 255.0f;
    }
    if (GLenum err = drain_gl_errors(); err != GL_NO_ERROR) {
        res.error = fmt::format("glReadPixels failed: {}", gl_error_name(err));
        return res;
    }

    res.image.width = w;
    res.image.height = h;
    res.image.rgba.resize(bottom_up.size());
    for (int y = 0; y < h; ++y) {
        const float* src = bottom_up.data() + static_cast<size_t>(h - 1 - y) * row_floats;
        std::copy(src, src + row_floats, res.image.rgba.data() + static_cast<size_t>(y) * row_floats);
    }
    res.ok = true;
    return res;
}

}  // namespace

// ---------------------------------------------------------------------------------------------------
// Renderer
// ---------------------------------------------------------------------------------------------------

Renderer::Renderer(std::unique_ptr<State> state) : state_(std::move(state)) {}
Renderer::~Renderer() = default;

std::unique_ptr<Renderer> Renderer::create(std::string* error) {
    std::string log;
    std::vector<DisplayCandidate> candidates = display_candidates(log);
    for (const DisplayCandidate& cand : candidates) {
        std::string why;
        if (auto st = try_display(cand, &why)) return std::unique_ptr<Renderer>(new Renderer(std::move(st)));
        log += "  " + cand.platform + " (" + cand.detail + "): " + why + "\n";
    }
    if (error) {
        *error = "no headless OpenGL ES 3 context available; EGL platforms tried:";
        *error += log.empty() ? " none" : "\n" + log;
        while (!error->empty() && error->back() == '\n') error->pop_back();
    }
    return nullptr;
}

std::string Renderer::renderer_name() const {
    if (state_->format_note.empty()) return state_->gl_renderer;
    return state_->gl_renderer + " [" + state_->format_note + "]";
}

std::string Renderer::platform_name() const { return state_->platform; }

RenderResult Renderer::render(const std::string& full_fragment_source_es300, const RenderOptions& opts) {
    if (!state_->make_current()) {
        RenderResult res;
        res.renderer = renderer_name();
        res.error = "eglMakeCurrent failed: " + egl_error_string();
        return res;
    }
    RenderResult res = render_current(*state_, full_fragment_source_es300, opts);
    state_->release_current();
    return res;
}

// ---------------------------------------------------------------------------------------------------
// render_shadertoy
// ---------------------------------------------------------------------------------------------------

RenderResult render_shadertoy(const std::string& user_code, const RenderOptions& opts) {
    static std::mutex mutex;
    static std::unique_ptr<Renderer> renderer;  // process-wide, created on first successful use
    std::lock_guard<std::mutex> lock(mutex);
    if (!renderer) {
        std::string error;
        renderer = Renderer::create(&error);
        if (!renderer) {
            RenderResult res;
            res.error = error;
            return res;
        }
    }
    return renderer->render(glsl::wrap_shadertoy(user_code), opts);
}

}  // namespace iqc::render
