#include "syntax/Lexer.h"

namespace iqc {

const char* token_description(Tok t) {
    switch (t) {
#define X(name, desc) \
    case Tok::name: return desc;
        IQC_TOKENS(X)
#undef X
    }
    return "token";
}

bool is_letter(char32_t c) {
    if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z')) return true;
    if (c >= 0xC0 && c <= 0x24F && c != 0xD7 && c != 0xF7) return true;  // Latin-1 and Latin Extended
    if (c >= 0x391 && c <= 0x3C9) return true;                            // Greek letters
    if (c == 0x3D1 || c == 0x3D5 || c == 0x3D6 || c == 0x3F0 || c == 0x3F1 || c == 0x3F5) return true;  // ϑ ϕ ϖ ϰ ϱ ϵ
    if (c >= 0x1E00 && c <= 0x1EFF) return true;
    if (c == 0x2113) return true;                                         // ℓ
    if (c >= 0x1D400 && c <= 0x1D7CB) return true;                        // mathematical alphanumerics
    return false;
}

namespace {

struct Lexer {
    const SourceManager& sm;
    FileId file;
    std::string_view text;
    std::vector<Token> out;
    bool space = false;
    bool line_start = true;

    void push(Tok k, uint32_t b, uint32_t e, std::string t = {}) {
        Token tok;
        tok.kind = k;
        tok.span = {file, b, e};
        tok.text = std::move(t);
        tok.space_before = space || line_start;
        tok.line_start = line_start;
        out.push_back(std::move(tok));
        space = false;
        line_start = (k == Tok::Newline);
    }

    static int superscript_digit(char32_t c) {
        switch (c) {
            case 0x2070: return 0;
            case 0x00B9: return 1;
            case 0x00B2: return 2;
            case 0x00B3: return 3;
            default: return (c >= 0x2074 && c <= 0x2079) ? int(c - 0x2070) : -1;
        }
    }
    static char subscript_char(char32_t c) {
        if (c >= 0x2080 && c <= 0x2089) return char('0' + (c - 0x2080));
        switch (c) {
            case 0x1D62: return 'i';
            case 0x2C7C: return 'j';
            case 0x2096: return 'k';
            case 0x2098: return 'm';
            case 0x2099: return 'n';
            default: return 0;
        }
    }
    static const char* fraction(char32_t c) {
        switch (c) {
            case 0xBD: return "1/2";
            case 0xBC: return "1/4";
            case 0xBE: return "3/4";
            case 0x2153: return "1/3";
            case 0x2154: return "2/3";
            case 0x2155: return "1/5";
            case 0x2156: return "2/5";
            case 0x2157: return "3/5";
            case 0x2158: return "4/5";
            case 0x2159: return "1/6";
            case 0x215A: return "5/6";
            case 0x215B: return "1/8";
            case 0x215C: return "3/8";
            case 0x215D: return "5/8";
            case 0x215E: return "7/8";
            default: return nullptr;
        }
    }

    void run(uint32_t begin, uint32_t end) {
        size_t i = begin;
        while (i < end) {
            uint32_t b = uint32_t(i);
            char c = text[i];
            if (c == ' ' || c == '\t' || c == '\r') { ++i; space = true; continue; }
            if (c == '\n') { ++i; push(Tok::Newline, b, b + 1); continue; }
            if (c == '#') {  // comment (extension)
                while (i < end && text[i] != '\n') ++i;
                space = true;
                continue;
            }
            if ((c >= '0' && c <= '9') || (c == '.' && i + 1 < end && text[i + 1] >= '0' && text[i + 1] <= '9')) {
                size_t j = i;
                while (j < end && std::isdigit(static_cast<unsigned char>(text[j]))) ++j;
                if (j + 1 < end + 1 && j < end && text[j] == '.' && !(j + 1 < end && text[j + 1] == '.')) {
                    ++j;
                    while (j < end && std::isdigit(static_cast<unsigned char>(text[j]))) ++j;
                }
                // Exponent only when digits follow: `2e-3` is 0.002, `2e` is 2·e.
                if (j < end && (text[j] == 'e' || text[j] == 'E')) {
                    size_t k = j + 1;
                    if (k < end && (text[k] == '+' || text[k] == '-')) ++k;
                    if (k < end && std::isdigit(static_cast<unsigned char>(text[k]))) {
                        while (k < end && std::isdigit(static_cast<unsigned char>(text[k]))) ++k;
                        j = k;
                    }
                }
                push(Tok::Number, b, uint32_t(j), std::string(text.substr(i, j - i)));
                i = j;
                continue;
            }
            if (c == '`') {
                size_t j = i + 1;
                while (j < end && text[j] != '`' && text[j] != '\n') ++j;
                if (j < end && text[j] == '`' && j == i + 1) {
                    push(Tok::Unknown, b, uint32_t(j + 1), "``");  // an empty name: the parser says so where it meets it
                    i = j + 1;
                } else if (j < end && text[j] == '`') {
                    push(Tok::Backtick, b, uint32_t(j + 1), std::string(text.substr(i + 1, j - i - 1)));
                    i = j + 1;
                } else {
                    push(Tok::Unknown, b, b + 1, "`");
                    i = i + 1;
                }
                continue;
            }
            // Two-character ASCII operators.
            if (i + 1 < end) {
                std::string_view two = text.substr(i, 2);
                Tok k = Tok::Unknown;
                if (two == "<=") k = Tok::Le;
                else if (two == ">=") k = Tok::Ge;
                else if (two == "!=") k = Tok::Neq;
                else if (two == "->") k = Tok::Arrow;
                else if (two == "||") k = Tok::DoubleBar;
                else if (two == "..") k = Tok::Ellipsis;
                if (k != Tok::Unknown) {
                    size_t e2 = i + 2;
                    if (k == Tok::Ellipsis && e2 < end && text[e2] == '.') ++e2;
                    push(k, b, uint32_t(e2));
                    i = e2;
                    continue;
                }
            }
            size_t j = i;
            char32_t cp = utf8::decode(text, j);
            if (is_letter(cp)) {
                std::string word;
                size_t k = i;
                while (k < end) {
                    size_t m = k;
                    char32_t d = utf8::decode(text, m);
                    if (!is_letter(d) && !utf8::is_combining(d)) break;
                    k = m;
                }
                word = std::string(text.substr(i, k - i));
                // `atan2` is one name.
                if (word == "atan" && k < end && text[k] == '2') word = "atan2", ++k;
                push(Tok::Word, b, uint32_t(k), word);
                i = k;
                continue;
            }
            if (int d = superscript_digit(cp); d >= 0 || cp == 0x207B || cp == 0x207A) {
                std::string s;
                size_t k = i;
                while (k < end) {
                    size_t m = k;
                    char32_t e = utf8::decode(text, m);
                    int dd = superscript_digit(e);
                    if (dd >= 0) s += char('0' + dd);
                    else if (e == 0x207B) s += '-';
                    else if (e == 0x207A) s += '+';
                    else break;
                    k = m;
                }
                push(Tok::Super, b, uint32_t(k), s);
                i = k;
                continue;
            }
            if (cp == 0x1D40 || cp == 0x1D57) { push(Tok::Super, b, uint32_t(j), "T"); i = j; continue; }  // ᵀ
            if (cp == 0x207F) { push(Tok::Super, b, uint32_t(j), "n"); i = j; continue; }
            if (char s = subscript_char(cp)) {
                std::string t;
                size_t k = i;
                while (k < end) {
                    size_t m = k;
                    char32_t e = utf8::decode(text, m);
                    char sc = subscript_char(e);
                    if (!sc) break;
                    t += sc;
                    k = m;
                }
                (void)s;
                push(Tok::Sub, b, uint32_t(k), t);
                i = k;
                continue;
            }
            if (const char* f = fraction(cp)) { push(Tok::Fraction, b, uint32_t(j), f); i = j; continue; }
            if (cp == 0x1D7D9) { push(Tok::Number, b, uint32_t(j), "𝟙"); i = j; continue; }  // 𝟙: I♥LA's ones block
            if (cp == 0x23A1) { push(Tok::LBracket, b, uint32_t(j)); i = j; continue; }     // ⎡ opens a matrix
            if (cp == 0x23A6) { push(Tok::RBracket, b, uint32_t(j)); i = j; continue; }     // ⎦ closes it
            if (cp == 0x23A4 || cp == 0x23A2 || cp == 0x23A5 || cp == 0x23A3) {               // ⎤ ⎢ ⎥ ⎣: its sides
                i = j;
                space = true;
                continue;
            }
            Tok k = Tok::Unknown;
            switch (cp) {
                case '+': k = Tok::Plus; break;
                case '-': case 0x2212: k = Tok::Minus; break;
                case '*': k = Tok::Star; break;
                case '/': k = Tok::Slash; break;
                case 0xF7: k = Tok::Divide; break;
                case 0x22C5: case 0xB7: case 0x2219: k = Tok::Dot; break;
                case 0x2218: k = Tok::Circle; break;
                case 0xD7: k = Tok::Cross; break;
                case '^': k = Tok::Caret; break;
                case '=': k = Tok::Eq; break;
                case 0x2260: k = Tok::Neq; break;
                case '<': k = Tok::Lt; break;
                case 0x2264: k = Tok::Le; break;
                case '>': k = Tok::Gt; break;
                case 0x2265: k = Tok::Ge; break;
                case 0x2208: k = Tok::In; break;
                case 0x2209: k = Tok::NotIn; break;
                case 0x2016: k = Tok::Norm; break;
                case '|': k = Tok::Bar; break;
                case 0x230A: k = Tok::LFloor; break;
                case 0x230B: k = Tok::RFloor; break;
                case 0x2308: k = Tok::LCeil; break;
                case 0x2309: k = Tok::RCeil; break;
                case 0x221A: k = Tok::Sqrt; break;
                case 0x2211: k = Tok::Sum; break;
                case '(': k = Tok::LParen; break;
                case ')': k = Tok::RParen; break;
                case '[': k = Tok::LBracket; break;
                case ']': k = Tok::RBracket; break;
                case '{': k = Tok::LBrace; break;
                case '}': k = Tok::RBrace; break;
                case ',': k = Tok::Comma; break;
                case ';': k = Tok::Semicolon; break;
                case ':': k = Tok::Colon; break;
                case '_': k = Tok::Underscore; break;
                case 0x2192: k = Tok::Arrow; break;
                case 0x211D: k = Tok::Reals; break;
                case 0x2124: k = Tok::Integers; break;
                case 0x2026: k = Tok::Ellipsis; break;
                case '\\': k = Tok::Backslash; break;
                case 0x2297: k = Tok::Kronecker; break;
                case 0x27E8: k = Tok::LAngle; break;
                case 0x27E9: k = Tok::RAngle; break;
                case 0x221E: k = Tok::Infinity; break;
                case 0xB1: k = Tok::PlusMinus; break;
                default: break;
            }
            // A BOM reads as whitespace. A stray combining mark (after a space or a digit: one after a letter is
            // part of the name) and a zero-width space are errors: as whitespace they made `3 ́ 4` read as 3·4 and
            // `a​b` as a·b without a word (a new user's trial).
            if (cp == 0xFEFF && b == 0) {  // a BOM starts the file; elsewhere it is a zero-width no-break space
                i = j;
                space = true;
                continue;
            }
            std::string t(text.substr(i, j - i));
            push(k, b, uint32_t(j), k == Tok::Unknown ? t : std::string());
            i = j;
        }
    }
};

}  // namespace

std::vector<Token> lex(const SourceManager& sm, FileId file, const std::vector<TextRange>& ranges) {
    Lexer lx{sm, file, sm.text(file), {}};
    size_t bytes = 0;
    for (const auto& r : ranges) bytes += r.end - r.begin;
    lx.out.reserve(bytes / 3 + 8);
    for (const auto& r : ranges) {
        lx.line_start = true;
        lx.space = false;
        lx.run(r.begin, r.end);
        if (lx.out.empty() || lx.out.back().kind != Tok::Newline) lx.push(Tok::Newline, r.end, r.end);
    }
    uint32_t end = ranges.empty() ? 0 : ranges.back().end;
    lx.push(Tok::End, end, end);
    return std::move(lx.out);
}

}  // namespace iqc
