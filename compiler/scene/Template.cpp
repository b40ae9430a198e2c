#include "scene/Template.h"

#include <stdexcept>
#include <vector>

namespace iqc {

std::string expand_template(const std::string& text, const TemplateArgs& args) {
    std::string out;
    std::vector<std::pair<bool, bool>> stack;  // (this block's condition, the enclosing output state)
    bool emitting = true;
    size_t i = 0;
    while (i < text.size()) {
        size_t open = text.find("{{", i);
        if (open == std::string::npos) {
            if (emitting) out.append(text, i, std::string::npos);
            break;
        }
        size_t close = text.find("}}", open);
        if (close == std::string::npos) throw std::runtime_error("template: unclosed {{");
        std::string tag = text.substr(open + 2, close - open - 2);
        bool block = tag.rfind("#if ", 0) == 0 || tag == "#else" || tag == "/if";
        // A block tag alone on its line removes the whole line.
        size_t line_begin = text.rfind('\n', open == 0 ? 0 : open - 1);
        line_begin = line_begin == std::string::npos ? 0 : line_begin + 1;
        size_t line_end = text.find('\n', close);
        bool alone = block && text.find_first_not_of(" \t", line_begin) == open &&
                     (line_end == std::string::npos || text.find_first_not_of(" \t", close + 2) == line_end);
        size_t chunk_end = alone ? line_begin : open;
        if (emitting && chunk_end > i) out.append(text, i, chunk_end - i);
        i = alone ? (line_end == std::string::npos ? text.size() : line_end + 1) : close + 2;
        if (tag.rfind("#if ", 0) == 0) {
            std::string flag = tag.substr(4);
            bool neg = !flag.empty() && flag[0] == '!';
            if (neg) flag = flag.substr(1);
            bool cond = args.flags.count(flag) > 0;
            if (neg) cond = !cond;
            stack.push_back({cond, emitting});
            emitting = emitting && cond;
        } else if (tag == "#else") {
            if (stack.empty()) throw std::runtime_error("template: {{#else}} without {{#if}}");
            emitting = stack.back().second && !stack.back().first;
        } else if (tag == "/if") {
            if (stack.empty()) throw std::runtime_error("template: {{/if}} without {{#if}}");
            emitting = stack.back().second;
            stack.pop_back();
        } else {
            auto it = args.values.find(tag);
            if (it == args.values.end()) throw std::runtime_error("template: no value for {{" + tag + "}}");
            if (emitting) out += it->second;
        }
    }
    if (!stack.empty()) throw std::runtime_error("template: unclosed {{#if}}");
    return out;
}

}  // namespace iqc
