#include "glsl/Validate.h"

#include <glslang/Public/ResourceLimits.h>
#include <glslang/Public/ShaderLang.h>

#include <algorithm>
#include <cctype>
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

size_t locate_shader_log(const std::string& log, FileId file, Diagnostics& diags) {
    const SourceManager& sm = diags.sources();
    const std::string_view text = sm.text(file);
    size_t lines = 1;
    for (char c : text) lines += c == '\n';
    auto number = [](std::string_view s, size_t& i) {  // digits at s[i] (at most 9), or -1
        long v = -1;
        for (size_t n = 0; i < s.size() && s[i] >= '0' && s[i] <= '9' && n < 9; ++i, ++n) v = (v < 0 ? 0 : v * 10) + (s[i] - '0');
        return v;
    };
    auto starts = [](std::string_view s, std::string_view p) { return s.substr(0, p.size()) == p; };
    size_t errors = 0;
    size_t at = 0;
    while (at < log.size()) {
        size_t nl = log.find('\n', at);
        std::string_view l(log.data() + at, (nl == std::string::npos ? log.size() : nl) - at);
        at = nl == std::string::npos ? log.size() : nl + 1;
        long line = -1, col = -1;
        bool warning = false;
        std::string_view message;
        size_t i = 0;
        if (number(l, i) >= 0 && i < l.size() && l[i] == ':') {  // Mesa: 0:LINE(COL): error: message
            ++i;
            line = number(l, i);
            if (line < 0 || i >= l.size() || l[i] != '(') continue;
            ++i;
            col = number(l, i);
            if (col < 0 || l.substr(i, 3) != "): ") continue;
            std::string_view rest = l.substr(i + 3);
            if (starts(rest, "error: ")) message = rest.substr(7);
            else if (starts(rest, "preprocessor error: ")) message = rest.substr(20);
            else if (starts(rest, "warning: ")) message = rest.substr(9), warning = true;
            else continue;
        } else if (starts(l, "ERROR: ") || starts(l, "WARNING: ")) {  // glslang: ERROR: NAME:LINE: message
            warning = l[0] == 'W';
            std::string_view rest = l.substr(warning ? 9 : 7);
            // NAME may hold colons: the first `:DIGITS: ` after it is the line.
            for (size_t k = 0; k < rest.size(); ++k) {
                if (rest[k] != ':') continue;
                size_t j = k + 1;
                long v = number(rest, j);
                if (v >= 0 && rest.substr(j, 2) == ": ") {
                    line = v;
                    message = rest.substr(j + 2);
                    break;
                }
            }
            if (line < 0 || message.find("compilation terminated") != std::string_view::npos) continue;
        } else {
            continue;
        }
        std::string msg(message);
        if (line < 1 || size_t(line) > lines) {
            // In the code the renderer wraps around the user's (Shadertoy's main): no line of the file to show.
            if (warning) continue;
            diags.error_nospan(msg);
            ++errors;
            continue;
        }
        const std::string_view lt = sm.line_text(file, uint32_t(line));
        size_t begin = size_t(lt.data() - text.data());
        size_t off = 0;
        if (col >= 1) off = std::min(size_t(col - 1), lt.size());
        else
            while (off < lt.size() && (lt[off] == ' ' || lt[off] == '\t')) ++off;
        // A name the message quotes (Mesa's `name', glslang's 'name' : ...) found on the line as a whole word
        // (the occurrence nearest the column) is a better place than the column, which Mesa gives for the
        // construct around it and glslang not at all.
        auto word = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
        for (size_t q = 0; q < msg.size(); ++q) {
            if (msg[q] != '`' && msg[q] != '\'') continue;
            size_t e = q + 1;
            while (e < msg.size() && word(msg[e])) ++e;
            if (e == q + 1 || e >= msg.size() || msg[e] != '\'') continue;
            const std::string_view name(msg.data() + q + 1, e - q - 1);
            size_t best = std::string_view::npos;
            for (size_t k = lt.find(name); k != std::string_view::npos; k = lt.find(name, k + 1)) {
                if ((k > 0 && word(lt[k - 1])) || (k + name.size() < lt.size() && word(lt[k + name.size()]))) continue;
                auto gap = [&](size_t x) { return x > off ? x - off : off - x; };
                if (best == std::string_view::npos || gap(k) < gap(best)) best = k;
            }
            if (best != std::string_view::npos) {
                off = best;
                break;
            }
        }
        size_t end = off;  // the token there: a name or a number, else one byte
        while (end < lt.size() && (std::isalnum(static_cast<unsigned char>(lt[end])) || lt[end] == '_' || lt[end] == '.')) ++end;
        if (end == off && off < lt.size()) ++end;
        Span span{file, uint32_t(begin + off), uint32_t(begin + end)};
        if (warning) diags.warning(span, std::move(msg));
        else {
            diags.error(span, std::move(msg));
            ++errors;
        }
    }
    return errors;
}

}  // namespace iqc::glsl
