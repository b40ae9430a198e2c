// Tokens of the math language (I♥LA as extended by I♥IQ).
#pragma once

#include <string>

#include "source/Source.h"

namespace iqc {

#define IQC_TOKENS(X)                                                                                    \
    X(Word, "name")              /* a run of letters and combining marks: split into names by the parser */ \
    X(Backtick, "`name`")        /* any text between backticks is one name */                              \
    X(Number, "number")                                                                                    \
    X(Newline, "end of line")                                                                              \
    X(End, "end of input")                                                                                 \
    X(Plus, "'+'")                                                                                         \
    X(Minus, "'-'")                                                                                        \
    X(Star, "'*'")                                                                                         \
    X(Slash, "'/'")                                                                                        \
    X(Divide, "'÷'")                                                                                       \
    X(Dot, "'⋅'")                                                                                          \
    X(Circle, "'∘'")                                                                                       \
    X(Cross, "'×'")                                                                                        \
    X(Caret, "'^'")                                                                                        \
    X(Eq, "'='")                                                                                           \
    X(Neq, "'≠'")                                                                                          \
    X(Lt, "'<'")                                                                                           \
    X(Le, "'≤'")                                                                                           \
    X(Gt, "'>'")                                                                                           \
    X(Ge, "'≥'")                                                                                           \
    X(In, "'∈'")                                                                                           \
    X(NotIn, "'∉'")                                                                                        \
    X(Norm, "'‖'")                                                                                         \
    X(DoubleBar, "'||'")                                                                                   \
    X(Bar, "'|'")                                                                                          \
    X(LFloor, "'⌊'")                                                                                       \
    X(RFloor, "'⌋'")                                                                                       \
    X(LCeil, "'⌈'")                                                                                        \
    X(RCeil, "'⌉'")                                                                                        \
    X(Sqrt, "'√'")                                                                                         \
    X(Sum, "'∑'")                                                                                          \
    X(LParen, "'('")                                                                                       \
    X(RParen, "')'")                                                                                       \
    X(LBracket, "'['")                                                                                     \
    X(RBracket, "']'")                                                                                     \
    X(LBrace, "'{'")                                                                                       \
    X(RBrace, "'}'")                                                                                       \
    X(Comma, "','")                                                                                        \
    X(Semicolon, "';'")                                                                                    \
    X(Colon, "':'")                                                                                        \
    X(Underscore, "'_'")                                                                                   \
    X(Arrow, "'→'")                                                                                        \
    X(Super, "superscript")      /* text: "2", "-1", "T" */                                                \
    X(Sub, "subscript")          /* text: "1", "i" */                                                      \
    X(Fraction, "fraction")      /* text: "1/2" */                                                         \
    X(Reals, "'ℝ'")                                                                                        \
    X(Integers, "'ℤ'")                                                                                     \
    X(Ellipsis, "'…'")                                                                                     \
    X(Backslash, "'\\'")       /* A \ b: solve */                                                         \
    X(Kronecker, "'⊗'")                                                                                    \
    X(LAngle, "'⟨'")                                                                                       \
    X(RAngle, "'⟩'")                                                                                       \
    X(Infinity, "'∞'")                                                                                     \
    X(PlusMinus, "'±'")                                                                                    \
    X(Unknown, "character")

enum class Tok {
#define X(name, desc) name,
    IQC_TOKENS(X)
#undef X
};

const char* token_description(Tok t);

struct Token {
    Tok kind = Tok::End;
    Span span;
    std::string text;           // the name (without backticks), number, superscript or subscript text
    bool space_before = false;  // whitespace directly before this token
    bool line_start = false;    // first token on its line
    // For a name split out of a longer letter run (`dot` -> d, o, t): the whole run, so an undefined
    // letter is reported once, as the word the user wrote. Empty (file 0, 0..0) otherwise.
    Span word;
};

}  // namespace iqc
