// GLSL names: readable spellings of math names (`N̂` -> `N_hat`, `α` -> `alpha`, `p'` -> `p_prime`) and
// the one place that knows GLSL's reserved words and built-ins, so no emitted name can collide with them.
#pragma once

#include <set>
#include <string>

namespace iqc::glsl {

// A valid GLSL identifier spelling the math name (not yet checked for collisions).
std::string identifier(const std::string& math_name);

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
};

}  // namespace iqc::glsl
