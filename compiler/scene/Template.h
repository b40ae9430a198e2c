// A tiny template engine for runtime_templates/: `{{NAME}}` is replaced by a value, and
// `{{#if FLAG}} … {{#else}} … {{/if}}` keeps one branch (blocks nest; `{{#if !FLAG}}` negates). An
// effect the scene does not ask for is a flag that is off, so its code is simply not in the output.
// A line holding only a block tag disappears with its newline.
#pragma once

#include <map>
#include <set>
#include <string>

namespace iqc {

struct TemplateArgs {
    std::map<std::string, std::string> values;
    std::set<std::string> flags;
};

// Throws std::runtime_error on an unknown placeholder or unbalanced blocks (a bug in a template).
std::string expand_template(const std::string& text, const TemplateArgs& args);

}  // namespace iqc
