// The engine targets that go through SPIR-V: Vulkan GLSL 4.50 compiled to SPIR-V 1.0 by glslang and checked
// by SPIRV-Tools' validator (the rules of the SPIR-V specification and Vulkan 1.0's environment), and HLSL
// cross-compiled from that SPIR-V by SPIRV-Cross and re-checked by glslang's HLSL front end. Anything these
// reject is a bug in iqc: the driver reports it with exit code 3 and writes nothing.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "glsl/Validate.h"

namespace iqc::glsl {

struct SpirvResult {
    bool ok = false;
    std::string log;              // the first failing stage's messages when not ok
    std::vector<uint32_t> words;  // the SPIR-V module (little-endian 32-bit words; entry point "main")
};

// Compiles a complete Vulkan GLSL fragment shader (`#version 450`, resources at descriptor set 0) to SPIR-V
// for Vulkan 1.0 and validates the module.
SpirvResult compile_vulkan_fragment(const std::string& source);

struct HlslResult {
    bool ok = false;
    std::string log;
    std::string text;  // Shader Model 5.0 pixel shader, entry point "main"
};

// HLSL from a validated SPIR-V fragment shader: uniform blocks become cbuffers at register(bN) for binding N,
// the data texture a Texture2D and SamplerState at t/s registers of its binding; then parsed and linked by
// glslang's HLSL front end.
HlslResult spirv_to_hlsl(const std::vector<uint32_t>& words);

// Parses and links an HLSL pixel shader (entry point "main") with glslang's HLSL front end.
ValidationResult validate_hlsl_fragment(const std::string& text);

}  // namespace iqc::glsl
