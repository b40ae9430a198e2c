// The wgsl target: WebGPU Shading Language translated from the validated SPIR-V of the spirv target, so the
// runtime has one source (runtime_templates/scene.glsl) for every target. The translation reads the module as
// glslang writes it (structured control flow, SPIR-V 1.0, Shader capability, GLSL.std.450) and writes:
//  * every SPIR-V function as a WGSL function (pointer parameters as ptr<function, T>), each SSA value as a
//    `let` or, when another block reads it, a function-scope `var`; OpPhi through a `var` set on each edge;
//  * structured control flow (OpSelectionMerge, OpLoopMerge, OpSwitch) as if/else, loop with continuing and
//    `break if`, and switch; the block order and nesting come from the merge and continue targets;
//  * uniform blocks as `var<uniform>` at @group(DescriptorSet) @binding(Binding) with their std140 offsets
//    kept (@size on members; arrays or matrix columns whose std140 stride differs from WGSL's are arrays of
//    a one-member struct of that size), so a host fills the bytes `--meta` describes for the spirv target;
//  * the data texture (a combined image sampler read only with texelFetch) as texture_2d<f32> read with
//    textureLoad at the sampler's binding;
//  * the entry point as `@fragment fn fs_main` (@builtin(position) in, @location(0) colour and
//    @builtin(frag_depth) out) and a full-screen triangle `@vertex fn vs_main` (draw 3 vertices).
// Anything else (an opcode, type or decoration the translation does not know) is an error: the driver
// reports it as an internal error (exit 3) and writes nothing. The result is validated by Tint in the test
// suite (tests/browser/wgsl.test.mjs: Dawn for Node); no WGSL compiler is available in-process.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace iqc::glsl {

struct WgslResult {
    bool ok = false;
    std::string log;   // why the translation failed, when not ok
    std::string text;  // the WGSL module
};

// WGSL from a SPIR-V fragment shader module (little-endian words, one entry point, as validated by
// compile_vulkan_fragment). Deterministic: the same words give the same text.
WgslResult spirv_to_wgsl(const std::vector<uint32_t>& words);

// A Shadertoy shader (`mainImage(out vec4, in vec2)`, GLSL ES 3.00 as pasted into shadertoy.com) as WGSL:
// compiled as Vulkan GLSL 4.50 with Shadertoy's inputs in the std140 block `ShadertoyInputs` at @group(0)
// @binding(0) (kShadertoyInputs: iResolution 0, iTime 12, iTimeDelta 16, iFrameRate 20, iFrame 24, iMouse 32,
// iDate 48; 64 bytes), fragCoord with Shadertoy's origin (bottom left), alpha 1; then spirv_to_wgsl.
// iChannel textures are not declared. `user_error`: glslang rejected the shader (its messages, lines of the
// shader's own file, in `log`); otherwise a failure is the translation's (a bug: exit 3).
struct ShadertoyWgsl {
    bool ok = false;
    bool user_error = false;
    std::string log;
    std::string text;
    // The inputs block's name: ShadertoyInputs, or ShadertoyInputs_2, ... where the shader uses that name itself
    // (so do the wrapper's output, iqc_fragColor, and its local: never a name the shader declares).
    std::string inputs_block = "ShadertoyInputs";
};
ShadertoyWgsl shadertoy_to_wgsl(const std::string& code);

struct ShadertoyInput {
    const char* name;
    const char* type;  // float, int, vec3, vec4
    int offset;
};
inline constexpr ShadertoyInput kShadertoyInputs[] = {
    {"iResolution", "vec3", 0}, {"iTime", "float", 12}, {"iTimeDelta", "float", 16}, {"iFrameRate", "float", 20},
    {"iFrame", "int", 24},      {"iMouse", "vec4", 32},  {"iDate", "vec4", 48},
};
inline constexpr int kShadertoyInputsBytes = 64;

}  // namespace iqc::glsl
