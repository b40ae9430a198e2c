#include "sema/Hints.h"

#include <algorithm>
#include <cctype>
#include <map>

#include <fmt/format.h>

#include "resources/Embedded.h"
#include "source/Source.h"

namespace iqc {

namespace {

struct Greek {
    const char* ascii;
    const char* letter;
};
const Greek kGreek[] = {
    {"alpha", "α"}, {"beta", "β"},   {"gamma", "γ"},   {"delta", "δ"},   {"epsilon", "ε"}, {"zeta", "ζ"},
    {"eta", "η"},   {"theta", "θ"},  {"iota", "ι"},    {"kappa", "κ"},   {"lambda", "λ"},  {"mu", "μ"},
    {"nu", "ν"},    {"xi", "ξ"},     {"omicron", "ο"}, {"pi", "π"},      {"rho", "ρ"},     {"sigma", "σ"},
    {"tau", "τ"},   {"upsilon", "υ"}, {"phi", "φ"},    {"chi", "χ"},     {"psi", "ψ"},     {"omega", "ω"},
    {"Gamma", "Γ"}, {"Delta", "Δ"},  {"Theta", "Θ"},   {"Lambda", "Λ"},  {"Xi", "Ξ"},      {"Pi", "Π"},
    {"Sigma", "Σ"}, {"Upsilon", "Υ"}, {"Phi", "Φ"},    {"Psi", "Ψ"},     {"Omega", "Ω"},
};

struct Habit {
    const char* word;
    const char* hint;
};
// GLSL (and other programming) habits, with the math I♥LA writes instead.
const Habit kHabits[] = {
    {"dot", "for the dot product write u⋅v (or uᵀv)"},
    {"cross", "for the cross product write u × v"},
    {"vec2", "write a vector as (a, b)"},
    {"vec3", "write a vector as (a, b, c)"},
    {"vec4", "write a vector as (a, b, c, d)"},
    {"mat2", "write a matrix as [a b; c d]"},
    {"mat3", "write a matrix as [a b c; d e f; g h i]"},
    {"mat4", "write a matrix as [a b c d; …] with four rows"},
    {"PI", "write π"},
    {"norm", "write ‖v‖ for the length of v"},
    {"transpose", "write Aᵀ (or A^T)"},
    {"inverse", "write A⁻¹ (or A^(-1))"},
    {"determinant", "write |A|"},
    {"reflect", "the reflection of I about the unit normal N̂ is I - 2(N̂⋅I)N̂"},
    {"lerp", "write mix(a, b, t)"},
    {"saturate", "write clamp(x, 0, 1)"},
    {"inversesqrt", "write 1/√x"},
    {"float", "numbers need no conversion: write the value itself"},
    {"translate", "to move a shape, give the scene's transform T((x, y, z)) (import T from transformations in a module)"},
    {"rotate", "to rotate a shape, give the scene's transform `R_x`(θ), `R_y`(θ) or `R_z`(θ)"},
    {"scale", "to scale a shape, give the scene's transform S((a, b, c))"},
    {"radians", "write the angle times π/180"},
    {"degrees", "write the angle times 180/π"},
    {"sum", "write ∑_i x_i (or sum_i x_i)"},
};

}  // namespace

std::optional<std::string> greek_letter(std::string_view ascii_name) {
    for (const Greek& g : kGreek)
        if (ascii_name == g.ascii) return std::string(g.letter);
    return std::nullopt;
}

std::optional<std::string> word_hint(std::string_view word) {
    for (const Habit& h : kHabits)
        if (word == h.word) return std::string(h.hint);
    if (auto g = greek_letter(word)) return fmt::format("write {}", *g);
    return std::nullopt;
}

std::optional<std::string> match_key(const std::string& key, const std::vector<std::string>& candidates, bool* accept) {
    *accept = false;
    // theta -> θ, theta_1 -> θ_1
    size_t cut = key.find('_');
    if (auto g = greek_letter(key.substr(0, cut))) {
        std::string greek = *g + (cut == std::string::npos ? "" : key.substr(cut));
        for (const auto& c : candidates)
            if (c == greek) {
                *accept = true;
                return c;
            }
    }
    // kd -> k_d: the same letters without underscores or backticks.
    auto bare = [](const std::string& s) {
        std::string out;
        for (char c : s)
            if (c != '_' && c != '`') out += c;
        return out;
    };
    std::optional<std::string> found;
    for (const auto& c : candidates)
        if (c != key && bare(c) == bare(key)) {
            if (found) return std::nullopt;  // ambiguous
            found = c;
        }
    return found;
}

std::string spell_letters(std::string_view word, std::string_view sep) {
    std::string out;
    size_t i = 0;
    while (i < word.size()) {
        size_t b = i;
        utf8::decode(word, i);
        while (i < word.size()) {
            size_t j = i;
            if (!utf8::is_combining(utf8::decode(word, j))) break;
            i = j;
        }
        if (!out.empty()) out += sep;
        out += word.substr(b, i - b);
    }
    return out;
}

namespace {
const std::map<std::string, std::vector<std::string>, std::less<>>& library_index();

// The module an embedded file is (`stdlib/noise.iql` -> noise), or empty where it is no standard-library module.
std::string_view stdlib_module(std::string_view path) {
    if (path.rfind("stdlib/", 0) != 0 || path.size() <= 11 || path.substr(path.size() - 4) != ".iql") return {};
    return path.substr(7, path.size() - 11);
}
}  // namespace

std::vector<std::string> library_modules_of(std::string_view name) {
    auto it = library_index().find(name);
    return it == library_index().end() ? std::vector<std::string>{} : it->second;
}

std::vector<std::string> library_module_names() {
    std::vector<std::string> names;
    for (const EmbeddedFile& f : embedded_resources())
        if (std::string_view m = stdlib_module(f.path); !m.empty()) names.emplace_back(m);
    return names;
}

std::vector<std::string> library_function_names() {
    std::vector<std::string> names;
    for (const auto& [n, modules] : library_index()) names.push_back(n);
    return names;
}

namespace {
const std::map<std::string, std::vector<std::string>, std::less<>>& library_index() {
    // The functions each library module defines: a line that starts with a name of two or more letters (in backticks
    // or not) and its parameters, `name(…) = …` (a one-letter name, x or f, is a value's in other modules).
    static const std::map<std::string, std::vector<std::string>, std::less<>> index = [] {
        std::map<std::string, std::vector<std::string>, std::less<>> out;
        for (const EmbeddedFile& f : embedded_resources()) {
            const std::string module(stdlib_module(f.path));
            if (module.empty()) continue;
            std::string_view text = f.contents;
            for (size_t at = 0; at < text.size();) {
                size_t end = text.find('\n', at);
                if (end == std::string_view::npos) end = text.size();
                std::string_view line = text.substr(at, end - at);
                at = end + 1;
                const bool ticked = !line.empty() && line[0] == '`';
                size_t k = ticked ? 1 : 0, start = k;
                while (k < line.size() && (std::isalnum(static_cast<unsigned char>(line[k])) || line[k] == '_')) ++k;
                if (k < start + 2 || (ticked && (k >= line.size() || line[k++] != '`'))) continue;  // (one letter: a value's)
                if (k >= line.size() || line[k] != '(' || line.find(") = ", k) == std::string_view::npos) continue;
                if (line[k - 1 - (ticked ? 1 : 0)] == '_') continue;  // (a sequence's recurrence, w_(k+1) = …)
                std::vector<std::string>& modules = out[std::string(line.substr(start, k - start - (ticked ? 1 : 0)))];
                if (std::find(modules.begin(), modules.end(), module) == modules.end()) modules.push_back(module);
            }
        }
        for (auto& [n, modules] : out) std::sort(modules.begin(), modules.end());
        return out;
    }();
    return index;
}
}  // namespace

std::string import_spelling(std::string_view name) {
    const bool ticked = std::any_of(name.begin(), name.end(), [](char c) { return c == '_' || std::isdigit(static_cast<unsigned char>(c)); });
    return ticked ? fmt::format("`{}`", name) : std::string(name);
}

}  // namespace iqc
