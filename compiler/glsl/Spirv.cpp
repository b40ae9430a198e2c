#include "glsl/Spirv.h"

#include "glsl/Validate.h"

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>
#include <spirv-tools/libspirv.hpp>
#include <spirv_cross/spirv_hlsl.hpp>

#include <mutex>

namespace iqc::glsl {


SpirvResult compile_vulkan_fragment(const std::string& source) {
    SpirvResult r;
    {
        std::lock_guard<std::mutex> lock(glslang_mutex());
        glslang::TShader shader(EShLangFragment);
        const char* strings[] = {source.c_str()};
        const char* names[] = {"iqc"};
        shader.setStringsWithLengthsAndNames(strings, nullptr, names, 1);
        shader.setEnvInput(glslang::EShSourceGlsl, EShLangFragment, glslang::EShClientVulkan, 100);
        shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_0);
        shader.setEnvTarget(glslang::EShTargetSpv, glslang::EShTargetSpv_1_0);
        auto msgs = EShMessages(EShMsgSpvRules | EShMsgVulkanRules);
        if (!shader.parse(GetDefaultResources(), 450, ECoreProfile, false, false, msgs)) {
            r.log = shader.getInfoLog();
            return r;
        }
        glslang::TProgram program;
        program.addShader(&shader);
        if (!program.link(msgs)) {
            r.log = program.getInfoLog();
            return r;
        }
        glslang::SpvOptions options;
        options.validate = false;  // SPIRV-Tools validates below, with its messages
        std::vector<unsigned int> words;
        glslang::GlslangToSpv(*program.getIntermediate(EShLangFragment), words, &options);
        r.words.assign(words.begin(), words.end());
    }
    spvtools::SpirvTools tools(SPV_ENV_VULKAN_1_0);
    std::string messages;
    tools.SetMessageConsumer([&](spv_message_level_t, const char*, const spv_position_t& at, const char* message) {
        messages += "SPIR-V word " + std::to_string(at.index) + ": " + message + "\n";
    });
    if (!tools.Validate(r.words)) {
        r.log = messages.empty() ? "SPIRV-Tools rejected the module" : messages;
        r.words.clear();
        return r;
    }
    r.ok = true;
    return r;
}

HlslResult spirv_to_hlsl(const std::vector<uint32_t>& words) {
    HlslResult r;
    try {
        spirv_cross::CompilerHLSL hlsl(words);
        spirv_cross::CompilerHLSL::Options options;
        options.shader_model = 50;
        hlsl.set_hlsl_options(options);
        r.text = hlsl.compile();
    } catch (const std::exception& e) {
        r.log = std::string("SPIRV-Cross: ") + e.what();
        return r;
    }
    ValidationResult v = validate_hlsl_fragment(r.text);
    r.ok = v.ok;
    r.log = v.log;
    return r;
}

ValidationResult validate_hlsl_fragment(const std::string& text) {
    ValidationResult r;
    std::lock_guard<std::mutex> lock(glslang_mutex());
    glslang::TShader shader(EShLangFragment);
    const char* strings[] = {text.c_str()};
    const char* names[] = {"iqc.hlsl"};
    shader.setStringsWithLengthsAndNames(strings, nullptr, names, 1);
    shader.setEntryPoint("main");
    shader.setEnvInput(glslang::EShSourceHlsl, EShLangFragment, glslang::EShClientVulkan, 100);
    shader.setEnvClient(glslang::EShClientVulkan, glslang::EShTargetVulkan_1_0);
    shader.setEnvTarget(glslang::EShTargetSpv, glslang::EShTargetSpv_1_0);
    auto msgs = EShMessages(EShMsgReadHlsl | EShMsgSpvRules | EShMsgVulkanRules);
    if (!shader.parse(GetDefaultResources(), 500, ENoProfile, false, false, msgs)) {
        r.log = std::string("glslang (HLSL): ") + shader.getInfoLog();
        return r;
    }
    glslang::TProgram program;
    program.addShader(&shader);
    if (!program.link(msgs)) {
        r.log = std::string("glslang (HLSL): ") + program.getInfoLog();
        return r;
    }
    r.ok = true;
    return r;
}

}  // namespace iqc::glsl
