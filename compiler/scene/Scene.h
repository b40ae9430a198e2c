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
struct ParamOverride {
    std::string name;
    std::vector<double> value;
    Span span;
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
    Span span;
};

struct CameraDesc {
    std::array<double, 3> position{0, 0, -1};
    std::array<double, 3> target{0, 0, 5};
    double fov = 60;  // vertical, degrees
};

struct RenderDesc {
    int max_steps = 128;
    double max_dist = 100;
    double hit = 1e-3;
    std::array<double, 3> background{0.05, 0.05, 0.08};
};

struct SceneDesc {
    std::string path;
    std::string title;
    FileId file = 0;
    std::vector<ModuleSource> modules;  // defined by the scene/document and its includes
    std::vector<InstanceDesc> instances;
    CameraDesc camera;
    RenderDesc render;
};

// Reads and parses `path` into `out`; reports problems to `diags` (returns false on error).
bool load_scene(const std::string& path, SourceManager& sm, Diagnostics& diags, SceneDesc& out);

// The byte offset of a 1-based line/column (columns in code points) counted from `base` in `file`.
uint32_t offset_at(const SourceManager& sm, FileId file, uint32_t base, uint32_t line, uint32_t col);

}  // namespace iqc
