// Scene loading: the three input forms (a TOML scene `.iq`, an I♥IQ document `.md`, a module file `.iql`)
// become one SceneDesc: the modules it defines (with where their text is), camera and render settings, and
// the shape instances. Schema errors (unknown fields, wrong TOML types) are located diagnostics.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "source/Source.h"
#include "syntax/Lexer.h"

namespace iqc {

struct ModuleSource {
    std::string name;
    FileId file = 0;
    std::vector<TextRange> ranges;  // the module's text (a document's blocks with one name join)
    Span where;                     // for "defined here" notes
    std::string origin;             // "document", "scene", "include", "stdlib"
};

// A parameter override from `shape_params` / `material_params`.
// A value is a number, an array of numbers (a vector), an array of arrays of numbers (a matrix's rows), or
// a string holding a constant expression ("√2", "(cos(π/6), sin(π/6), 0)"), evaluated when the scene is read.
struct ParamOverride {
    std::string name;
    std::vector<double> value;  // components, row-major
    Span span;
    int rows = 0;               // an array of rows: how many (0: not written as rows)
    int cols = 0;
};

struct InstanceDesc {
    std::string name;  // explicit, or "" (then `<type>_<n>`)
    Span name_span;
    std::string type;
    Span type_span;
    std::string material;  // "" for the default material
    Span material_span;
    std::optional<ModuleSource> transform;
    std::vector<ParamOverride> shape_params, material_params;
    double bound = 0;  // object-space bounding sphere radius at the origin (`bound = R`); 0: none
    Span bound_span;
    // A glow around the instance (`glow = [r, g, b]`, linear colour; `glow_radius`, world units): light the
    // primary ray gathers by passing near it (docs/look.md). No glow: nothing of it is computed.
    std::optional<std::array<double, 3>> glow;
    double glow_radius = 0.2;
    Span glow_span;
    Span span;
};

struct CameraDesc {
    std::array<double, 3> position{0, 0, -1};
    std::array<double, 3> target{0, 0, 5};
    double fov = 60;  // vertical, degrees
    bool orbit = false;
    Span position_span;  // where `position` is written (empty: the default)
};

enum class March { Fixed, Sphere, Relaxed, Auto, Segment };
enum class Normals { Central, Forward, Tetrahedron, Analytic };
enum class DebugView { None, Normals, Steps, Depth };
enum class Shadows { None, Hard, Soft };

// The largest `max_steps` a scene may set (Scene.cpp refuses more; the fixed march's thickness warning says when
// the step it advises would need more to reach as far).
inline constexpr int kMaxStepsSetting = 100000;

struct RenderDesc {
    March march = March::Sphere;
    Span march_span;  // where `march` is written (empty: the default)
    int max_steps = 128;
    Span max_steps_span;  // where `max_steps` is written (empty: the default, which grows with shortened steps)
    double max_dist = 100;
    double hit = 1e-3;
    bool hit_relative = false;  // hit_mode = "relative": the tolerance grows with distance (hit · t)
    Normals normals = Normals::Tetrahedron;
    std::array<double, 3> background{0.05, 0.05, 0.08};
    // A sky gradient instead of one colour (`background = { zenith = [...], horizon = [...], ground = [...] }`):
    // what rays that hit nothing see, reflections and refraction included.
    bool sky_gradient = false;
    std::array<double, 3> zenith{0.3, 0.5, 0.85};
    std::array<double, 3> ground{0.0, 0.0, 0.0};  // below the horizon (default: the horizon colour)
    bool has_ground = false;
    double stars = 0;  // a night sky's star field above the horizon (`stars` in the gradient), in [0, 1]: 0 none
    // Output transform (docs/look.md): the colour is computed in linear light, then exposed, tone mapped and
    // encoded. Default: sRGB for TOML scenes, linear (the thesis's look) for I♥IQ documents.
    std::optional<bool> srgb;
    enum class Tonemap { None, Reinhard, ACES } tonemap = Tonemap::None;
    double exposure = 1;
    // Grading after the encoding (0: off): a vignette darkening the corners by this share, and a contrast
    // S-curve mixed in by this share (both in [0, 1]).
    double vignette = 0;
    double contrast = 0;
    double relaxation = 1.6;    // ω of the relaxed method
    double step = 0;            // the fixed method's step (0: max_dist, or the scene box's diagonal where shorter, / max_steps)
    DebugView debug = DebugView::None;
};

struct EffectsDesc {
    Shadows shadows = Shadows::None;
    double shadow_softness = 16;  // k of the soft-shadow penumbra
    bool ao = false;
    double fog = 0;               // density; 0 is off
    std::optional<std::array<double, 3>> fog_color;  // default: the background
    bool fog_exp2 = false;        // fog_mode = "exp2": 1 - exp(-(density·t)²) instead of 1 - exp(-density·t)
    int reflections = 0;          // bounces
    bool refraction = false;
    int antialias = 1;            // samples per pixel side
    Span shadows_span, reflections_span, refraction_span;  // the values as written (warnings)
};

// A light (docs/look.md): `point` (at `position`) and `sun` (directional: `direction` points toward it) are
// bound to materials' `P_L`, `C_L` and cast shadows; `sky` (a hemisphere from +y) and `bounce` (a fill from
// `direction`: light bounced off the ground) are indirect light, bound to materials' `C_A` and darkened by
// ambient occlusion only.
enum class LightKind { Point, Sun, Sky, Bounce };
struct LightDesc {
    std::string name;
    LightKind kind = LightKind::Point;
    std::array<double, 3> position{0, 0, 0};
    std::array<double, 3> direction{0, 1, 0};  // sun: toward the sun; bounce: toward where the bounce comes from
    bool has_direction = false;
    std::array<double, 3> color{1, 1, 1};
    Span span;
};

// A smooth union of instances (`[[blends]]`): their distances joined by Quilez's polynomial smooth minimum
// of radius k, their materials mixed by the same weights.
struct BlendDesc {
    std::vector<std::pair<std::string, Span>> shapes;  // instance names as written
    double radius = 0.25;
    Span span;
};

struct SceneDesc {
    std::string path;
    std::string title;
    FileId file = 0;
    std::vector<ModuleSource> modules;  // defined by the scene/document and its includes
    std::vector<InstanceDesc> instances;
    CameraDesc camera;
    RenderDesc render;
    EffectsDesc effects;
    std::vector<LightDesc> lights;
    std::vector<BlendDesc> blends;
    bool thesis_look = false;  // an I♥IQ document or a module alone: linear output unless [render] output says
    bool srgb() const { return render.srgb.value_or(!thesis_look); }
};

// Reads and parses `path` into `out`; reports problems to `diags` (returns false on error).
bool load_scene(const std::string& path, SourceManager& sm, Diagnostics& diags, SceneDesc& out);

}  // namespace iqc
