// GLSL names: readable spellings of math names (`N̂` -> `N_hat`, `α` -> `alpha`, `p'` -> `p_prime`) and
// the one place that knows GLSL's reserved words and built-ins, so no emitted name can collide with them.
#pragma once

#include <map>
#include <set>
#include <string>
#include <string_view>

namespace iqc::glsl {

// A valid GLSL identifier spelling the math name (not yet checked for collisions), of at most kMaxIdentifier
// characters (a longer spelling is cut and ends in a hash of the whole).
inline constexpr size_t kMaxIdentifier = 64;
std::string identifier(const std::string& math_name);

// Text that is safe to put after `// ` in generated GLSL, whatever the user wrote (titles, instance, light
// and module names, descriptions, formulas): one line (every line terminator: LF, CR, VT, FF, NEL U+0085,
// LINE/PARAGRAPH SEPARATOR U+2028/U+2029, becomes a space; runs of white space become one), no NUL or
// other control character, no `/*` or `*/`, no backslash at the end (a line continuation would pull the
// next line of code into the comment), valid UTF-8 (invalid bytes become U+FFFD). The one function every
// comment built from user text goes through. Invisible format characters (bidirectional overrides and isolates,
// zero-width characters, BOM) are spelled out as <U+XXXX>.
std::string comment_text(std::string_view text);

// GLSL ES 3.00 / 3.30 keywords, reserved words, built-in functions and variables, and names the runtime uses.
bool is_reserved(const std::string& name);

// Hands out unique names in one scope; a name that is reserved or taken gets a suffix (`_2`, `_3`, ...).
class Namer {
public:
    explicit Namer(const Namer* parent = nullptr) : parent_(parent) {}
    std::string unique(const std::string& math_name);
    void reserve(const std::string& name) { used_.insert(name); }
    bool taken(const std::string& name) const;

private:
    const Namer* parent_;
    std::set<std::string> used_;
    std::map<std::string, int> next_suffix_;  // per base name: the next suffix to try (0: the bare name first)
};

}  // namespace iqc::glsl
