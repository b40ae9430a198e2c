#include "scene/ThreeModule.h"

#include <nlohmann/json.hpp>


#include "glsl/Names.h"
#include "resources/Embedded.h"
#include "scene/Template.h"

namespace iqc {

namespace {

// A JSON text as a JavaScript literal safe anywhere: ASCII only (ensure_ascii escapes U+2028/U+2029 too), and
// '<', '>', '&' (which occur in JSON only inside strings) as \u escapes.
std::string js_literal(const nlohmann::json& j) {
    std::string text = j.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace), out;
    out.reserve(text.size());
    for (char c : text) {
        if (c == '<') out += "\\u003c";
        else if (c == '>') out += "\\u003e";
        else if (c == '&') out += "\\u0026";
        else out += c;
    }
    return out;
}

// A comment line's text: one line (glsl::comment_text), and no "</" so that a module inlined into a page's
// <script> element cannot end it.
std::string js_comment(const std::string& text) {
    std::string line = glsl::comment_text(text), out;
    for (size_t i = 0; i < line.size(); ++i) {
        out += line[i];
        if (line[i] == '<' && i + 1 < line.size() && line[i + 1] == '/') out += ' ';
    }
    return out;
}

}  // namespace

std::string three_module(std::string_view shader, std::string_view meta_json, std::string_view source) {
    nlohmann::json meta = nlohmann::json::parse(meta_json);
    for (const auto& p : meta["parameters"]) {
        std::string type = p.value("type", std::string());
        if (p.value("storage", std::string()) == "uniform" && type.size() > 4 && type.rfind("mat", 0) == 0 && type.find('x') != std::string::npos)
            throw ThreeUnsupported{"the threejs target cannot take " + p.value("instance", std::string()) + "'s parameter " +
                                   p.value("name", std::string()) + " (a " + type +
                                   " uniform: three.js has no setter for non-square matrices); write it as vectors, or use --target webgl2"};
    }
    std::string body(shader);
    const std::string version = "#version 300 es\n";
    if (body.rfind(version, 0) == 0) body.erase(0, version.size());
    TemplateArgs args;
    args.values = {{"TITLE", js_comment(meta.value("title", std::string("iqc scene")))},
                   {"VERSION", IQC_VERSION},
                   {"SOURCE", js_comment(std::string(source))},
                   {"META", js_literal(meta)},
                   {"SHADER", js_literal(nlohmann::json(body))}};
    return expand_template(std::string(*embedded_file("runtime_templates/three.mjs")), args);
}

}  // namespace iqc
