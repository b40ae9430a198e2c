#include "glsl/Validate.h"

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>

#include <memory>
#include <mutex>

namespace iqc::glsl {

namespace {
struct Process {
    Process() { glslang::InitializeProcess(); }
    ~Process() { glslang::FinalizeProcess(); }
};
}  // namespace

std::mutex& glslang_mutex() {
    static Process process;
    static std::mutex mu;
    return mu;
}

ValidationResult validate_fragment(const std::string& source, Profile profile) {
    std::lock_guard<std::mutex> lock(glslang_mutex());
    ValidationResult r;
    glslang::TShader shader(EShLangFragment);
    const char* strings[] = {source.c_str()};
    const char* names[] = {"iqc"};
    shader.setStringsWithLengthsAndNames(strings, nullptr, names, 1);
    int version = profile == Profile::Es300 ? 300 : 330;
    EProfile prof = profile == Profile::Es300 ? EEsProfile : ECoreProfile;
    EShMessages msgs = EShMsgDefault;
    if (!shader.parse(GetDefaultResources(), version, prof, false, false, msgs)) {
        r.log = shader.getInfoLog();
        return r;
    }
    glslang::TProgram program;
    program.addShader(&shader);
    if (!program.link(msgs)) {
        r.log = program.getInfoLog();
        return r;
    }
    r.ok = true;
    return r;
}

}  // namespace iqc::glsl
