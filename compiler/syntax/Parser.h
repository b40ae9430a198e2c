// Parser: tokens -> AST of one module (recursive descent; each rule is written above its function).
//
// Before parsing, a pre-scan collects the names the module declares, assigns or imports. Letter runs
// are then split into names the way I♥LA reads them: a declared multi-letter name wins (longest first),
// otherwise every letter (with its combining marks) is its own name, so `xy` is `x` times `y`.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "syntax/Ast.h"
#include "syntax/Lexer.h"

namespace iqc {

struct ParseOptions {
    // Names known from outside the module (built-in functions, implicit imports), used to split letter runs.
    std::set<std::string> known_names;
    // True for a scene's `transform` string: a bare expression module.
    bool allow_header = true;
};

ast::Module parse_module(const SourceManager& sm, FileId file, const std::vector<TextRange>& ranges,
                         std::string name, const ParseOptions& opts, Diagnostics& diags);

}  // namespace iqc
