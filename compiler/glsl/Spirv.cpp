#include "glsl/Spirv.h"

#include "glsl/Validate.h"

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>
#include <glslang/SPIRV/GlslangToSpv.h>
#include <spirv-tools/libspirv.hpp>
#include <spirv_cross/spirv_hlsl.hpp>

#include <mutex>

namespace iqc::glsl {


namespace {

// The module without OpSourceContinued, OpSource, OpSourceExtension, OpName, OpMemberName, OpString, OpLine,
// OpNoLine and OpModuleProcessed (debug instructions: the SPIR-V specification, §3.32.2).
std::vector<uint32_t> without_debug_instructions(const std::vector<uint32_t>& words) {
    if (words.size() < 5) return words;
    std::vector<uint32_t> out(words.begin(), words.begin() + 5);
    out.reserve(words.size());
    for (size_t at = 5; at < words.size();) {
        uint32_t count = words[at] >> 16, op = words[at] & 0xffff;
        if (count == 0 || at + count > words.size()) return words;  // malformed: the validator says so
        bool debug = (op >= 2 && op <= 8) || op == 317 || op == 330;
        if (!debug) out.insert(out.end(), words.begin() + long(at), words.begin() + long(at + count));
        at += count;
    }
    return out;
}

}  // namespace

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
    // SPIRV-Tools' validator spends most of its time on the debug names when there are thousands (a scene of
    // 200 instances with slider transforms: 3.1 s with its 8,000 OpName/OpMemberName, 0.2 s without; 3,000
    // instances did not finish in minutes): the module is validated without its debug instructions, which
    // change nothing the rules check, and again with them only to word the messages when it fails.
    if (tools.Validate(without_debug_instructions(r.words))) {
        r.ok = true;
        return r;
    }
    messages.clear();
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
