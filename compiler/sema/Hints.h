// Hints for what writers of GLSL and of papers type that I♥LA reads differently.
//
// I♥LA's names are one letter, so an undeclared word such as `dot` is d·o·t; when one of its letters is
// undefined the checker reports the word once, with the hint below (`dot` -> "write u⋅v", `vec3` ->
// "(a, b, c)", `pi` -> "π"). ASCII names of Greek letters (`theta`) map to the letter, for hints and for
// scene parameter keys.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace iqc {

// A hint for a word typed out of habit (GLSL functions and types, ASCII Greek names), or nullopt.
std::optional<std::string> word_hint(std::string_view word);

// The Greek letter an ASCII name spells (`theta` -> θ, `Omega` -> Ω), or nullopt.
std::optional<std::string> greek_letter(std::string_view ascii_name);

// The parameter a scene key means when it is not a parameter's exact name: a Greek letter written with its
// ASCII name (`theta` -> θ, `theta_1`), or the same name without its underscore (`kd` -> k_d) when exactly one
// candidate matches. `accept` is set when the key may be taken as that parameter (the Greek spellings);
// otherwise the result is a suggestion only.
std::optional<std::string> match_key(const std::string& key, const std::vector<std::string>& candidates, bool* accept);

// The letters a word is read as, joined by `sep` (`rad`, "·" -> r·a·d).
std::string spell_letters(std::string_view word, std::string_view sep);

// The standard-library modules (stdlib/*.iql, embedded) that define a function of this name (`fbm` -> noise,
// `smooth_union` -> operators), in name order: what an import of it reads `name from module`. Empty where none does.
std::vector<std::string> library_modules_of(std::string_view name);

// The standard library's module names (stdlib/*.iql: noise, operators, …), for "did you mean".
std::vector<std::string> library_module_names();

// Every function name library_modules_of knows (for "did you mean").
std::vector<std::string> library_function_names();

// How an import writes a name: in backticks where it has an underscore or a digit (`` `value_noise` ``, `` `fbm2` ``).
std::string import_spelling(std::string_view name);

}  // namespace iqc
