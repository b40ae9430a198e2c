// The scene's GLSL backend: decides where each global lives on the target, declares it, emits every IR
// function the runtime calls, and describes the parameters for hosts (`--meta`).
//
// Storage:
//  * Shadertoy: everything is a constant (`const`, arrays as `const T name[N]`), written compactly for
//    large tables; parameters are constants the user edits.
//  * webgl2 / glsl330: parameters are uniforms (a slider each). Per-instance data (arrays: a group's
//    parameters, and its compile-time tables of kMinTableForBuffer or more elements) go into std140 uniform
//    blocks of at most 16 KiB each (WebGL2 guarantees 16 KiB per block and 12 blocks per fragment shader);
//    past that, into one RGBA32F data texture (`iqc_data`, read with `iqc_fetch(texel)`: one texel per
//    vector, one per matrix column). Plain uniforms past WebGL2's 224 vectors go into blocks too. Prepared
//    globals are private variables iqc_prepare writes.
// The host fills blocks and the texture from ShaderInputs (iqc render) or from `--meta` (blocks and texture
// as base64 bytes; each parameter's byte offsets or texel components), as the html page does.
#pragma once

#include <cstdint>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "scene/SceneLower.h"
#include "source/Source.h"

namespace iqc {

enum class Target;

// What a host sets before drawing a uniform-target shader (defaults of every parameter).
struct ShaderInputs {
    struct Uniform {
        std::string name;
        std::vector<double> value;  // GLSL order (matrices column-major)
        bool integer = false;
    };
    struct Block {
        std::string name;
        int binding = 0;
        std::vector<uint8_t> bytes;  // std140
    };
    struct Texture {
        std::string name;            // "" when none
        int width = 0, height = 0;
        std::vector<float> rgba;     // width·height texels
    };
    std::vector<Uniform> uniforms;  // parameters
    // The camera's uniforms with the scene's camera (iqc_camera_position, iqc_camera_basis, iqc_camera_focal,
    // iqc_projection: see runtime_templates/scene.glsl); a host drawing with its own camera sets its own.
    std::vector<Uniform> camera;
    // Every plain uniform a host sets: the parameters, then the camera.
    std::vector<Uniform> all_uniforms() const {
        std::vector<Uniform> all = uniforms;
        all.insert(all.end(), camera.begin(), camera.end());
        return all;
    }
    std::vector<Block> blocks;
    Texture texture;
};

struct SceneCode {
    std::string declarations;  // parameters, lights, data, blocks, texture, per-pixel values
    std::string functions;     // the modules and the scene functions, callees first
    nlohmann::ordered_json parameters = nlohmann::ordered_json::array();
    nlohmann::ordered_json lights = nlohmann::ordered_json::array();
    nlohmann::ordered_json blocks = nlohmann::ordered_json::array();
    nlohmann::ordered_json texture;  // null when none
    ShaderInputs inputs;
    int uniform_vectors = 0;         // plain uniforms, in vec4 slots
};

struct BackendOptions {
    bool constants = true;     // Shadertoy: every global is a constant
    // Vulkan GLSL (the spirv target): no plain uniforms; parameters go into std140 blocks at set 0, bindings
    // from 1 (binding 0 is the template's IqcInputs), the data texture at the binding after the last block.
    bool vulkan = false;
    // three.js (the threejs target): no uniform blocks (three.js lays out its own uniform groups and cannot take
    // std140 bytes); per-instance data goes into the data texture, a DataTexture there.
    bool blocks = true;
    bool instrument = false;   // iqc_scene is emitted as iqc_scene_counted (the runtime counts evaluations)
    // The most scene evaluations one pixel's shader invocation makes (the march's step cap, the normal's taps,
    // shadow marches, AO samples, bounces, antialiasing samples): the emitter keeps the rolled sums' loop
    // iterations within llvmpipe's 65,535 per invocation (glsl::Emitter::limit_loop_iterations). 0: unknown.
    double evaluations_per_pixel = 0;
    // Comments for module functions by IR function name ("torus" -> "shape torus").
    std::map<std::string, std::string> comments;
};

SceneCode emit_scene(const SceneIR& scene, const BackendOptions& o, Diagnostics& d);

}  // namespace iqc
