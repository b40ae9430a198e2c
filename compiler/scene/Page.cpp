#include "scene/Page.h"

#include <cstdio>
#include <stdexcept>

#include "resources/Embedded.h"

namespace iqc {

namespace {

void append_escape(std::string& out, unsigned code) {
    char buf[8];
    std::snprintf(buf, sizeof buf, "\\u%04x", code);
    out += buf;
}

// Escapes the characters that matter to an HTML parser inside <script>; true when `c` at `i` was handled.
bool html_escape(std::string& out, std::string_view s, size_t& i) {
    unsigned char c = static_cast<unsigned char>(s[i]);
    if (c == '<' || c == '>' || c == '&') {
        append_escape(out, c);
        return true;
    }
    // U+2028 / U+2029 (E2 80 A8 / E2 80 A9): line terminators in older JavaScript.
    if (c == 0xE2 && i + 2 < s.size() && static_cast<unsigned char>(s[i + 1]) == 0x80 &&
        (static_cast<unsigned char>(s[i + 2]) == 0xA8 || static_cast<unsigned char>(s[i + 2]) == 0xA9)) {
        append_escape(out, static_cast<unsigned char>(s[i + 2]) == 0xA8 ? 0x2028 : 0x2029);
        i += 2;
        return true;
    }
    return false;
}

void fill_placeholder(std::string& text, std::string_view key, std::string_view value) {
    size_t at = text.find(key);
    if (at == std::string::npos) throw std::logic_error("page template lacks " + std::string(key));
    text.replace(at, key.size(), value);
}

}  // namespace

std::string json_string_for_html(std::string_view text) {
    std::string out = "\"";
    for (size_t i = 0; i < text.size(); ++i) {
        unsigned char c = static_cast<unsigned char>(text[i]);
        if (html_escape(out, text, i)) continue;
        switch (c) {
            case '"': out += "\\\""; break;
            case '\\': out += "\\\\"; break;
            case '\n': out += "\\n"; break;
            case '\r': out += "\\r"; break;
            case '\t': out += "\\t"; break;
            default:
                if (c < 0x20) append_escape(out, c);
                else out += static_cast<char>(c);
        }
    }
    return out + "\"";
}

std::string json_for_html(std::string_view json) {
    std::string out;
    out.reserve(json.size());
    for (size_t i = 0; i < json.size(); ++i)
        if (!html_escape(out, json, i)) out += json[i];
    return out;
}

std::string html_page(std::string_view webgl2_shader, std::string_view meta_json, std::string_view live_reload) {
    std::string page(*embedded_file("runtime_templates/page.html"));
    // Substitute the script last: it is the only part that could contain a placeholder-like text.
    fill_placeholder(page, "{{LIVE_RELOAD}}", live_reload);
    fill_placeholder(page, "{{META_JSON}}", json_for_html(meta_json));
    fill_placeholder(page, "{{SHADER_JSON}}", json_string_for_html(webgl2_shader));
    return page;
}

}  // namespace iqc
