// The `threejs` target: an ES module for three.js (runtime_templates/three.mjs) holding the webgl2 shader
// (compiled without uniform blocks: per-instance data in the data texture) and its --meta description, with
// createMaterial(camera) / createMesh(camera): a RawShaderMaterial whose camera uniforms follow a three.js
// PerspectiveCamera every frame and whose gl_FragDepth composites raymarched surfaces with meshes.
//
// The shader and the JSON are written as JavaScript string / object literals by a JSON serializer with every
// non-ASCII character, '<', '>', '&' and the line separators U+2028/U+2029 escaped, so no input can end a literal
// early or read as markup where the module is inlined into a page.
#pragma once

#include <string>
#include <string_view>

namespace iqc {

// `shader`: the webgl2 (three.js variant) shader; `meta_json`: its --meta; `title`, `source`: for the header
// comment (sanitized here). Throws nlohmann::json errors only on a malformed `meta_json` (an internal error).
// What the threejs target cannot express (a non-square matrix uniform): the input's error, not iqc's.
struct ThreeUnsupported {
    std::string message;
};
// Throws ThreeUnsupported for a parameter three.js cannot upload.
std::string three_module(std::string_view shader, std::string_view meta_json, std::string_view source);

}  // namespace iqc
