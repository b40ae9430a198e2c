// Lexer: UTF-8 text -> tokens.
//
// Letters are grouped into Word tokens without deciding what they mean: `xy` may be one declared name or
// `x` times `y`, and only the parser (which has seen the module's declarations) can tell. Everything else
// (Unicode operators, superscripts, subscripts, fractions, backtick names, numbers) becomes one token
// each. Newlines are tokens: statements end at them. `#` starts a comment to the end of the line (an
// iqc extension; I♥LA has no comments).
#pragma once

#include <vector>

#include "syntax/Token.h"

namespace iqc {

struct TextRange {
    uint32_t begin = 0, end = 0;  // byte offsets into the file
};

// Lexes the given ranges of `file` (a module may be spread over several Markdown code blocks); each range
// ends with a Newline token, the last with End. Unknown characters become Unknown tokens: the parser
// reports them where they matter (descriptions may contain anything).
std::vector<Token> lex(const SourceManager& sm, FileId file, const std::vector<TextRange>& ranges);

bool is_letter(char32_t c);

}  // namespace iqc
