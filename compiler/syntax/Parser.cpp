#include "syntax/Parser.h"

#include <cctype>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <fmt/format.h>
#include <limits>

#include "source/Limits.h"
#include "syntax/WordSplit.h"

#include "sema/Builtins.h"

namespace iqc {

using namespace ast;

const char* ast::binop_spelling(BinOp op) {
    switch (op) {
        case BinOp::Add: return "+";
        case BinOp::Sub: return "-";
        case BinOp::Juxtapose: return "juxtaposition";
        case BinOp::Star: return "*";
        case BinOp::Dot: return "⋅";
        case BinOp::Div: return "/";
        case BinOp::Hadamard: return "∘";
        case BinOp::Cross: return "×";
        case BinOp::Solve: return "\\";
        case BinOp::Kronecker: return "⊗";
        case BinOp::Frobenius: return ":";
        case BinOp::PlusMinus: return "±";
        case BinOp::Eq: return "=";
        case BinOp::Neq: return "≠";
        case BinOp::Lt: return "<";
        case BinOp::Le: return "≤";
        case BinOp::Gt: return ">";
        case BinOp::Ge: return "≥";
        case BinOp::And: return "and";
        case BinOp::Or: return "or";
    }
    return "?";
}

namespace {

const std::set<std::string> kKeywords = {"where", "given", "from", "if", "otherwise", "and", "or", "in",
                                         "default", "shape", "material", "scalar", "vector", "matrix", "for", "sum"};

bool is_name_token(const Token& t) { return t.kind == Tok::Word || t.kind == Tok::Backtick; }

// Whether a word is a keyword (a length filter first: most words are one letter).
bool is_keyword(const std::string& w) { return w.size() >= 2 && w.size() <= 9 && kKeywords.count(w) > 0; }
bool is_kw(const Token& t, const char* kw) { return t.kind == Tok::Word && t.text == kw; }

// Pre-scan: names the module assigns, declares, defines as functions or imports.
std::set<std::string> prescan(const std::vector<Token>& toks) {
    std::set<std::string> known;
    // Sequences (`z_(k+1) = ... for k ∈ 1..N`, the `for` possibly on a later line after a piecewise
    // step): their elements `z_1`, `z_9` stay subscripts.
    std::set<std::string> sequences;
    for (size_t k = 0; k + 2 < toks.size(); ++k) {
        if (!toks[k].line_start || !is_name_token(toks[k]) || toks[k + 1].kind != Tok::Underscore ||
            toks[k + 2].kind != Tok::LParen)
            continue;
        int depth = 0;
        for (size_t j = k + 2; j < toks.size() && toks[j].kind != Tok::Newline && toks[j].kind != Tok::End; ++j) {
            if (toks[j].kind == Tok::LParen) ++depth;
            if (toks[j].kind == Tok::RParen && --depth == 0) {
                if (toks[j + 1].kind == Tok::Eq) sequences.insert(toks[k].text);
                break;
            }
        }
    }
    size_t i = 0;
    while (i < toks.size()) {
        size_t line_end = i;
        while (line_end < toks.size() && toks[line_end].kind != Tok::Newline && toks[line_end].kind != Tok::End)
            ++line_end;
        // Scan every position in the line where a declaration, assignment or import may begin.
        for (size_t s = i; s < line_end; ++s) {
            bool starts = (s == i) || is_kw(toks[s - 1], "where") || is_kw(toks[s - 1], "given") ||
                          toks[s - 1].kind == Tok::Semicolon ||
                          (toks[s - 1].kind == Tok::Comma && s >= 2);
            if (!starts || !is_name_token(toks[s])) continue;
            // name list: NAME[_SUB] {, NAME[_SUB]}
            std::vector<std::string> names;
            size_t k = s, last = s;  // `last`: where the list's last name starts
            while (k < line_end && is_name_token(toks[k])) {
                last = k;
                std::string n = toks[k].text;
                if (k + 2 < line_end && toks[k + 1].kind == Tok::Underscore && !toks[k + 1].space_before &&
                    (toks[k + 2].kind == Tok::Word || toks[k + 2].kind == Tok::Backtick) && !toks[k + 2].space_before) {
                    // x_i ∈ ℝ³ (a sequence), q_i = … or B_i,j = … (element-wise): the name is x, q or B.
                    k += 2;
                    if (k + 2 < line_end && toks[k + 1].kind == Tok::Comma && !toks[k + 1].space_before &&
                        toks[k + 2].kind == Tok::Word && !toks[k + 2].space_before)
                        k += 2;
                } else if (k + 1 < line_end && toks[k + 1].kind == Tok::Sub && !toks[k + 1].space_before &&
                           !std::isdigit(static_cast<unsigned char>(toks[k + 1].text[0]))) {
                    k += 1;  // xᵢ
                } else if (k + 2 < line_end && toks[k + 1].kind == Tok::Underscore && !toks[k + 1].space_before &&
                           toks[k + 2].kind == Tok::Number && !toks[k + 2].space_before && !sequences.count(n)) {
                    names.push_back(n);  // x_1 = … and x_1 ∈ ℝ are names of their own (an iqc extension)
                    n += "_" + toks[k + 2].text;
                    k += 2;
                }
                names.push_back(n);
                ++k;
                if (k < line_end && toks[k].kind == Tok::Comma) { ++k; continue; }
                break;
            }
            if (k >= line_end) continue;
            const Token& t = toks[k];
            bool decl = t.kind == Tok::In || t.kind == Tok::Colon || is_kw(t, "in");
            bool imp = is_kw(t, "from");
            bool assign = t.kind == Tok::Eq && names.size() == 1;
            bool func = false;
            if (t.kind == Tok::LParen && names.size() == 1) {
                // NAME ( NAME {, NAME} ) =
                size_t m = k + 1;
                std::vector<std::string> params;
                while (m < line_end && is_name_token(toks[m])) {
                    params.push_back(toks[m].text);
                    ++m;
                    if (m < line_end && toks[m].kind == Tok::Comma) ++m;
                    else break;
                }
                if (m + 1 < line_end && toks[m].kind == Tok::RParen && toks[m + 1].kind == Tok::Eq) {
                    func = true;
                    for (auto& p : params) known.insert(p);
                }
            }
            if (decl || imp || assign || func)
                for (auto& n : names) known.insert(n);
            // A list starting at a later name of this one ends the same way with fewer names: nothing new,
            // unless it is the last name alone (then `NAME =` or `NAME(...)` may apply). Skipping keeps the
            // pre-scan linear on long lists.
            if (last > s) s = last - 1;
        }
        i = line_end + 1;
    }
    return known;
}

// Replaces each Word token by the names it spells (see the header comment).
// `known`: every name the module may use; `splitters`: the same names as automata (the module's own names,
// and the names known from outside, whose automaton is shared between modules).
std::vector<Token> split_words(const std::vector<Token>& toks, const std::set<std::string>& known,
                               const std::vector<const WordSplitter*>& splitters) {
    std::vector<Token> out;
    out.reserve(toks.size() + toks.size() / 4);
    for (size_t i = 0; i < toks.size(); ++i) {
        const Token& t = toks[i];
        bool after_from = i > 0 && is_kw(toks[i - 1], "from");
        if (t.kind != Tok::Word || is_keyword(t.text) || known.count(t.text) || after_from) {
            out.push_back(t);
            continue;
        }
        bool first = true;
        for (auto [b, len] : split_word(t.text, splitters)) {
            Token piece;  // not a copy of `t`: its text may be a 100,000-letter run
            piece.kind = t.kind;
            piece.text = t.text.substr(b, len);
            piece.span = {t.span.file, uint32_t(t.span.begin + b), uint32_t(t.span.begin + b + len)};
            piece.space_before = first && t.space_before;
            piece.line_start = first && t.line_start;
            if (len < t.text.size()) {
                piece.word = t.span;
                // vec3(…), mat4(…): the digit belongs to the GLSL word.
                if (i + 1 < toks.size() && toks[i + 1].kind == Tok::Number && !toks[i + 1].space_before &&
                    toks[i + 1].text.size() == 1)
                    piece.word.end = toks[i + 1].span.end;
            }
            out.push_back(std::move(piece));
            first = false;
        }
    }
    return out;
}

enum class Ctx { Top, Paren, Bracket, Brace, Bars };

class Parser {
public:
    Parser(const SourceManager& sm, std::vector<Token> toks, std::set<std::string> known, Diagnostics& d)
        : sm_(sm), toks_(std::move(toks)), known_(std::move(known)), diags_(d) {}

    Module parse(std::string name, bool allow_header);

private:
    const SourceManager& sm_;
    std::vector<Token> toks_;
    std::set<std::string> known_;
    Diagnostics& diags_;
public:
    std::set<std::string> functions_;  // names defined as local functions or imported
private:
    size_t pos_ = 0;
    std::vector<Ctx> ctx_{Ctx::Top};
    int in_condition_ = 0;  // inside a piecewise condition: `<` compares (elsewhere it may open ⟨u, v⟩)
    bool colon_ends_ = false;  // a default's value: `:` starts the description, not A : B
    int depth_ = 0;        // grammar nesting (limits::kMaxNesting)

    struct Bail {};  // unwinds to the statement loop after an error

    bool newline_insensitive() const { return ctx_.back() == Ctx::Paren || ctx_.back() == Ctx::Bars; }
    const Token& cur() {
        if (newline_insensitive())
            while (toks_[pos_].kind == Tok::Newline) ++pos_;
        return toks_[pos_];
    }
    const Token& peek_raw(size_t k = 0) const { return toks_[std::min(pos_ + k, toks_.size() - 1)]; }
    bool at(Tok k) { return cur().kind == k; }
    bool at_kw(const char* kw) { return is_kw(cur(), kw); }
    const Token& advance() {
        const Token& t = cur();
        if (pos_ < toks_.size() - 1) ++pos_;
        return t;
    }
    bool accept(Tok k) {
        if (at(k)) { advance(); return true; }
        return false;
    }
    [[noreturn]] void fail(Span s, std::string msg) {
        diags_.error(s, std::move(msg));
        throw Bail{};
    }
    // `smooth_union(a, b) = …` reads as products of one-letter names (I♥LA's rule) and then an unexpected '=':
    // say so, and how to write a multi-letter function name.
    void suggest_backticks(Span start, Span eq) {
        if (start.file != eq.file || eq.begin <= start.begin) return;
        std::string_view head = sm_.text(eq.file).substr(start.begin, eq.begin - start.begin);
        size_t n = 0;
        while (n < head.size() && (std::isalnum(static_cast<unsigned char>(head[n])) || head[n] == '_')) ++n;
        if (n < 2 || n >= head.size() || head[n] != '(' || !std::isalpha(static_cast<unsigned char>(head[0]))) return;
        std::string name(head.substr(0, n));
        Diagnostic& d = diags_.error(eq, "unexpected '=' after the end of the statement");
        Diagnostics::note(d, Span{start.file, start.begin, static_cast<uint32_t>(start.begin + n)},
                          fmt::format("'{}' reads as a product of one-letter names; to define a function with this name, "
                                      "write it in backticks: `{}`(…) = …", name, name));
        throw Bail{};
    }
    // One more level of nesting (a parenthesis, a sign, one more operand of a chain such as a + b + …) at
    // `at`: past limits::kMaxNesting a located error, instead of a stack overflow here or in a later pass.
    void nest(limits::DepthGuard& g, Span at) {
        if (!g.enter())
            fail(at, fmt::format("the expression nests deeper than {} levels (parentheses, signs and the terms of "
                                 "one sum or product count one each): split it into named steps", limits::kMaxNesting));
    }
    // A size written in a type (the 3 of ℝ³ or ℝ^(3×4)): from 1 to limits::kMaxComponents, else a located error.
    int checked_dimension(const Token& t) {
        if (t.text.find_first_not_of("0123456789") != std::string::npos || t.text.find_first_not_of('0') == std::string::npos)
            fail(t.span, fmt::format("a size must be a positive integer, found {}", t.text));
        auto n = limits::checked_size(t.text);
        if (!n)
            fail(t.span, fmt::format("the size {} is too large: iqc allows at most {} components per vector or matrix",
                                     t.text, limits::kMaxComponents));
        return *n;
    }
    // A number literal's value: within the range of the 32-bit floats shaders compute in, else a located error.
    double literal_value(const Token& t) {
        double v = std::strtod(t.text.c_str(), nullptr);
        // Both range errors are reported without abandoning the statement, so that what it declares stays declared
        // (a parameter's default of 1e-46 was followed by "undefined name 'a'" at every use).
        if (!limits::fits_float(v)) {
            diags_.error(t.span, fmt::format("the number {} is outside the range of 32-bit floats (at most about 3.4e38), "
                                             "which shaders compute in", t.text));
            return std::copysign(double(std::numeric_limits<float>::max()), v);
        }
        // Below the smallest normal float a shader computes 0 (or a denormal a GPU may flush to 0): 1e-50 as
        // a guard, max(‖q‖, 1e-50), would guard nothing.
        // (A literal so small that even a double is 0, 1e-400, has a nonzero digit before its exponent.)
        bool written_nonzero = false;
        for (char c : t.text) {
            if (c == 'e' || c == 'E') break;
            written_nonzero |= c >= '1' && c <= '9';
        }
        if ((v != 0 || written_nonzero) && std::fabs(v) < double(std::numeric_limits<float>::min())) {
            diags_.error(t.span, fmt::format("the number {} is below the smallest normal 32-bit float (about 1.2e-38), which "
                                             "shaders compute in: it would be 0 there (a guard such as max(x, 1e-30) works)",
                                             t.text));
            return 0;
        }
        return v;
    }
    const Token& expect(Tok k, const char* what) {
        if (!at(k))
            fail(cur().span, fmt::format("expected {} {}, found {}", token_description(k), what, describe(cur())));
        return advance();
    }
    std::string describe(const Token& t) const {
        switch (t.kind) {
            case Tok::Word: return fmt::format("'{}'", t.text);
            case Tok::Backtick: return fmt::format("`{}`", t.text);
            case Tok::Number: return fmt::format("number {}", t.text);
            case Tok::Unknown: return t.text == "``" ? std::string("an empty name `` (write the name between the backticks)")
                                                     : fmt::format("'{}'", t.text);
            default: return token_description(t.kind);
        }
    }
    Span prev_span() const { return toks_[pos_ > 0 ? pos_ - 1 : 0].span; }
    // The letter run the current token starts (a word split into letters, or the token itself).
    Span word_span() const { const Token& t = toks_[pos_]; return t.word.end > t.word.begin ? t.word : t.span; }
    bool word_is(const char* w) const { return sm_.slice(word_span()) == w; }
    void skip_word() {
        Span w = word_span();
        while (toks_[pos_].kind == Tok::Word && toks_[pos_].span.begin >= w.begin && toks_[pos_].span.end <= w.end) ++pos_;
    }
    void skip_line() {
        while (toks_[pos_].kind != Tok::Newline && toks_[pos_].kind != Tok::End) ++pos_;
    }

    ExprPtr make(ExprKind k, Span s) { return std::make_unique<Expr>(k, s); }
    static ExprPtr clone_expr(const Expr& x) {
        auto e = std::make_unique<Expr>(x.kind, x.span);
        e->number = x.number;
        e->text = x.text;
        e->name_span = x.name_span;
        e->op = x.op;
        for (const auto& a : x.args) e->args.push_back(clone_expr(*a));
        for (const auto& r : x.rows) {
            e->rows.emplace_back();
            for (const auto& a : r) e->rows.back().push_back(clone_expr(*a));
        }
        for (const auto& i : x.indices) e->indices.push_back({i.expr ? clone_expr(*i.expr) : nullptr, i.span, i.value});
        if (x.otherwise) e->otherwise = clone_expr(*x.otherwise);
        return e;
    }
    ExprPtr binary(BinOp op, ExprPtr a, ExprPtr b) {
        auto e = make(ExprKind::Binary, Span::join(a->span, b->span));
        e->op = op;
        e->args.push_back(std::move(a));
        e->args.push_back(std::move(b));
        return e;
    }

    bool line_is_decl();
    bool line_is_import();
    void parse_line(Module& m);
    Stmt parse_statement();
    bool indexed_assignment();
    Stmt parse_indexed_assignment(std::pair<std::string, Span> name, Span start);
    bool elementwise_indices(Stmt& s);
    Decl parse_decl();
    TypeSpec parse_type(bool allow_function = true);
    bool compound_dim() const;
    ExprPtr parse_dim_expr();
    std::vector<std::pair<std::string, Span>> parse_name_list();
    std::pair<std::string, Span> parse_name();

    ExprPtr parse_condition();
    ExprPtr parse_comparison();
    ExprPtr parse_atom_comparison();
    bool parenthesized_condition() const;
    ExprPtr parse_expr();
    ExprPtr parse_unary();
    ExprPtr parse_mult();
    ExprPtr parse_operand();  // operand of an explicit operator: allows a leading sign
    ExprPtr parse_elem();
    ExprPtr parse_power();
    ExprPtr parse_postfix(bool exponent = false);
    ExprPtr parse_call(ExprPtr callee);
    bool function_power(ExprPtr& e);
    bool log_base(ExprPtr& e);
    ExprPtr parse_primary();
    ExprPtr parse_matrix(Span open);
    ExprPtr parse_piecewise(Span open);
    ExprPtr parse_sequence_literal(Span open, ExprPtr first);
    ExprPtr parse_inner(const Token& open);
    ExprPtr parse_sum(Span start);
    ExprPtr parse_sized_block(ExprPtr symbol);
    bool ascii_inner_ahead() const;
    bool double_bar_opens_abs() const;
    void split_double_bar();
    void parse_norm_subscript(Expr& norm);
    ExprPtr parse_delimited(ExprKind kind, Tok close, Span open, const char* what);
    bool starts_juxtaposed_operand();
    std::string statement_text(Span s) const;
};

std::string Parser::statement_text(Span s) const { return std::string(sm_.slice(s)); }

// name := WORD | `text` ; a subscripted name such as `k_d` is one name when the module declares it
std::pair<std::string, Span> Parser::parse_name() {
    const Token& t = cur();
    if (!is_name_token(t)) fail(t.span, fmt::format("expected a name, found {}", describe(t)));
    if (t.kind == Tok::Word && is_keyword(t.text))
        fail(t.span, fmt::format("'{}' is a keyword and cannot be used as a name", t.text));
    std::string n = t.text;
    Span s = t.span;
    advance();
    if (at(Tok::Underscore) && !cur().space_before) {
        const Token& sub = peek_raw(1);
        // (A name in backticks that is declared itself, `ab`_2 with `ab`_i a sequence, is subscripted even where
        // `ab_2` is declared too: the backticks say where the name ends. A trial's `ab`_2 read ab_2.)
        bool delimited = t.kind == Tok::Backtick && known_.count(n);
        if ((is_name_token(sub) || sub.kind == Tok::Number) && !sub.space_before && known_.count(n + "_" + sub.text) && !delimited) {
            advance();
            n += "_" + sub.text;
            s = Span::join(s, advance().span);
        }
    }
    return {n, s};
}

std::vector<std::pair<std::string, Span>> Parser::parse_name_list() {
    std::vector<std::pair<std::string, Span>> names;
    names.push_back(parse_name());
    while (accept(Tok::Comma)) names.push_back(parse_name());
    return names;
}

// Looks ahead: NAME {, NAME} (∈ | : | in)
bool Parser::line_is_decl() {
    size_t k = pos_;
    while (true) {
        if (!is_name_token(toks_[k])) return false;
        ++k;
        // x_i (a sequence), x_1 and `k_d` (names): the subscript is part of the declared name.
        if (toks_[k].kind == Tok::Underscore && !toks_[k].space_before && k + 1 < toks_.size() &&
            (is_name_token(toks_[k + 1]) || toks_[k + 1].kind == Tok::Number) && !toks_[k + 1].space_before) {
            k += 2;
            while (toks_[k].kind == Tok::Word && toks_[k].word.end > toks_[k].word.begin &&
                   toks_[k].word.begin == toks_[k - 1].word.begin)
                ++k;  // the other letters of a word such as `ij`
        } else if (toks_[k].kind == Tok::Sub && !toks_[k].space_before) {
            ++k;
        }
        if (toks_[k].kind == Tok::Comma) { ++k; continue; }
        break;
    }
    return toks_[k].kind == Tok::In || toks_[k].kind == Tok::Colon || is_kw(toks_[k], "in");
}

bool Parser::line_is_import() {
    size_t k = pos_;
    while (true) {
        if (!is_name_token(toks_[k])) return false;
        ++k;
        if (toks_[k].kind == Tok::Comma) { ++k; continue; }
        break;
    }
    return is_kw(toks_[k], "from");
}

// Whether the size at the current token is arithmetic on sizes (`p+1`, `2k`, `(p+1)`), not one number or name.
bool Parser::compound_dim() const {
    const Token& t = toks_[pos_];
    if (t.kind == Tok::LParen) return true;
    if (t.kind != Tok::Number && !is_name_token(t)) return false;
    const Token& n = toks_[pos_ + 1];
    return !(n.kind == Tok::Cross || n.kind == Tok::Comma || n.kind == Tok::RParen || (n.kind == Tok::Word && n.text == "x"));
}

// dim_expr := dim_term {(+ | -) dim_term}     dim_term := dim_factor {[⋅ | * | /] dim_factor}
// dim_factor := NUMBER | NAME | ( dim_expr )   (`x` and `×` separate the two sizes)
ExprPtr Parser::parse_dim_expr() {
    std::function<ExprPtr()> expr, term, factor;
    factor = [&]() -> ExprPtr {
        const Token& t = cur();
        if (t.kind == Tok::Number) {
            auto e = make(ExprKind::Number, t.span);
            e->number = std::strtod(t.text.c_str(), nullptr);
            e->text = t.text;
            advance();
            return e;
        }
        if (is_name_token(t) && !(t.kind == Tok::Word && t.text == "x")) {
            auto e = make(ExprKind::Name, t.span);
            e->text = t.text;
            e->name_span = t.span;
            advance();
            return e;
        }
        if (t.kind == Tok::LParen) {
            limits::DepthGuard depth(depth_);
            nest(depth, t.span);
            advance();
            ExprPtr e = expr();
            e->span = Span::join(t.span, expect(Tok::RParen, "to close the size").span);
            return e;
        }
        fail(t.span, fmt::format("expected a size (a number, a size symbol or arithmetic on them), found {}", describe(t)));
    };
    term = [&]() {
        ExprPtr lhs = factor();
        while (true) {
            BinOp op = BinOp::Juxtapose;
            if (at(Tok::Dot) || at(Tok::Star)) advance(), op = BinOp::Star;
            else if (at(Tok::Slash) || at(Tok::Divide)) advance(), op = BinOp::Div;
            else if (!(at(Tok::Number) || at(Tok::LParen) || (is_name_token(cur()) && !(at(Tok::Word) && cur().text == "x"))))
                break;
            lhs = binary(op, std::move(lhs), factor());
        }
        return lhs;
    };
    expr = [&]() {
        ExprPtr lhs = term();
        while (at(Tok::Plus) || at(Tok::Minus)) {
            BinOp op = at(Tok::Plus) ? BinOp::Add : BinOp::Sub;
            advance();
            lhs = binary(op, std::move(lhs), term());
        }
        return lhs;
    };
    return expr();
}

// type := ℝ [SUPER | ^ dims] | ℤ | R [^ dims] | Z | scalar | vector(n) | matrix(m, n) | type {, type} → type
TypeSpec Parser::parse_type(bool allow_function) {
    limits::DepthGuard depth(depth_);
    nest(depth, cur().span);
    TypeSpec ts;
    Span start = cur().span;
    auto parse_dim = [&](int& value, std::string& sym) {
        if (at(Tok::Number)) {
            const Token& t = advance();
            value = checked_dimension(t);
        } else if (is_name_token(cur())) {
            sym = advance().text;
            value = 0;
        } else {
            fail(cur().span, fmt::format("expected a size, found {}", describe(cur())));
        }
    };
    auto parse_dims = [&]() {  // after ℝ: ³ | ^3 | ^n | ^(m×n)
        if (at(Tok::Super) && !cur().space_before) {
            const Token& t = advance();
            if (t.text == "n") { ts.kind = TypeSpec::Vector; ts.sym_rows = "n"; ts.rows = 0; return; }
            int n = checked_dimension(t);
            ts.kind = n == 1 ? TypeSpec::Scalar : TypeSpec::Vector;
            ts.rows = n;
            return;
        }
        if (!accept(Tok::Caret)) return;
        if (accept(Tok::LParen)) {
            ctx_.push_back(Ctx::Paren);
            if (compound_dim()) ts.rows_expr = parse_dim_expr(), ts.rows = 0;
            else parse_dim(ts.rows, ts.sym_rows);
            if (accept(Tok::Cross) || (at(Tok::Word) && cur().text == "x" && (advance(), true)) || accept(Tok::Comma)) {
                if (compound_dim()) ts.cols_expr = parse_dim_expr(), ts.cols = 0;
                else parse_dim(ts.cols, ts.sym_cols);
                ts.kind = TypeSpec::Matrix;
            } else {
                ts.kind = TypeSpec::Vector;
            }
            ctx_.pop_back();
            expect(Tok::RParen, "to close the size");
        } else {
            parse_dim(ts.rows, ts.sym_rows);
            ts.kind = TypeSpec::Vector;
        }
        if (ts.kind == TypeSpec::Vector && ts.rows == 1 && ts.sym_rows.empty()) ts.kind = TypeSpec::Scalar;
    };
    bool no_params = allow_function && ((at(Tok::LBrace) && peek_raw(1).kind == Tok::RBrace) ||
                                        (at(Tok::Unknown) && cur().text == "∅"));
    if (no_params) {  // {} → T, ∅ → T: a function of no arguments
        if (at(Tok::LBrace)) advance();
        advance();
        if (!at(Tok::Arrow)) fail(cur().span, fmt::format("expected '→' after a function's empty argument list, found {}", describe(cur())));
        advance();
        TypeSpec f;
        f.kind = TypeSpec::Function;
        f.result = std::make_unique<TypeSpec>(parse_type(false));
        f.span = Span::join(start, prev_span());
        return f;
    }
    if (accept(Tok::Reals) || (at(Tok::Word) && cur().text == "R" && (advance(), true))) {
        ts.kind = TypeSpec::Scalar;
        parse_dims();
    } else if (accept(Tok::Integers) || (at(Tok::Word) && cur().text == "Z" && (advance(), true))) {
        ts.kind = TypeSpec::Integer;
    } else if (at_kw("scalar")) {
        advance();
        ts.kind = TypeSpec::Scalar;
    } else if (at_kw("vector")) {
        advance();
        expect(Tok::LParen, "after 'vector'");
        ctx_.push_back(Ctx::Paren);
        parse_dim(ts.rows, ts.sym_rows);
        ctx_.pop_back();
        expect(Tok::RParen, "to close 'vector('");
        ts.kind = (ts.rows == 1 && ts.sym_rows.empty()) ? TypeSpec::Scalar : TypeSpec::Vector;
    } else if (at_kw("matrix")) {
        advance();
        expect(Tok::LParen, "after 'matrix'");
        ctx_.push_back(Ctx::Paren);
        parse_dim(ts.rows, ts.sym_rows);
        expect(Tok::Comma, "between the sizes of 'matrix(m, n)'");
        parse_dim(ts.cols, ts.sym_cols);
        ctx_.pop_back();
        expect(Tok::RParen, "to close 'matrix('");
        ts.kind = TypeSpec::Matrix;
    } else {
        fail(cur().span, fmt::format("expected a type (ℝ, ℝⁿ, ℤ, an interval [a,b]), found {}", describe(cur())));
    }
    ts.span = Span::join(start, prev_span());
    // Function type: type {, type} → type
    if (allow_function && (at(Tok::Comma) || at(Tok::Arrow))) {
        size_t save = pos_;
        std::vector<TypeSpec> params;
        params.push_back(std::move(ts));
        bool ok = true;
        while (accept(Tok::Comma)) {
            if (!(at(Tok::Reals) || at(Tok::Integers) || at_kw("scalar") || at_kw("vector") || at_kw("matrix") ||
                  (at(Tok::Word) && (cur().text == "R" || cur().text == "Z")))) { ok = false; break; }
            params.push_back(parse_type(false));
        }
        if (ok && accept(Tok::Arrow)) {
            TypeSpec f;
            f.kind = TypeSpec::Function;
            f.params = std::move(params);
            f.result = std::make_unique<TypeSpec>(parse_type(false));
            f.span = Span::join(start, prev_span());
            return f;
        }
        pos_ = save;
        return std::move(params[0]);
    }
    return ts;
}

// decl := names (∈ | : | in) (type | interval {(x | ×) interval}) [default = expr] [: description]
Decl Parser::parse_decl() {
    Decl d;
    Span start = cur().span;
    while (true) {
        auto name = parse_name();  // x_1 and `k_d` are names; x_i is the sequence x with its index i
        std::string index;
        if (at(Tok::Underscore) && !cur().space_before && is_name_token(peek_raw(1)) && !peek_raw(1).space_before) {
            advance();
            const Token& t = advance();
            Span sub = t.span;
            index = t.text;
            if (t.word.end > t.word.begin) {
                sub = t.word;
                auto& e = diags_.error(Span::join(name.second, sub),
                                       fmt::format("the sequence '{}' needs a one-letter index, not '{}'", name.first,
                                                   std::string(sm_.slice(t.word))));
                Diagnostics::note(e, name.second, fmt::format("for a parameter named {}_{}, write it in backticks: `{}_{}`",
                                                              name.first, sm_.slice(t.word), name.first, sm_.slice(t.word)));
                throw Bail{};
            }
            name.second = Span::join(name.second, sub);
        } else if (at(Tok::Sub) && !cur().space_before && !std::isdigit(static_cast<unsigned char>(cur().text[0]))) {
            index = cur().text;
            name.second = Span::join(name.second, advance().span);
        } else if (at(Tok::Sub) && !cur().space_before) {
            // x₁ ∈ ℝ: a subscript digit is a component of x, not part of a name (a trial got "expected '∈' ...,
            // found subscript" and "undefined name 'x'" at each use). Declared as x_1, with the spelling to use.
            Span sub = cur().span;
            const std::string digits = cur().text;
            diags_.error(Span::join(name.second, sub),
                         fmt::format("'{}{}' is a component of {}, not a name: to declare a parameter named {}_{}, write {}_{} (and "
                                     "use it as {}_{})", name.first, sm_.slice(sub), name.first, name.first, digits, name.first,
                                     digits, name.first, digits));
            throw Bail{};
        }
        d.names.push_back(name);
        d.indices.push_back(index);
        if (!accept(Tok::Comma)) break;
    }
    if (!(accept(Tok::In) || accept(Tok::Colon) || (at_kw("in") && (advance(), true))))
        fail(cur().span, fmt::format("expected '∈' in the declaration, found {}", describe(cur())));
    if (at(Tok::LBracket)) {
        while (true) {
            Interval iv;
            Span open = expect(Tok::LBracket, "to open an interval").span;
            ctx_.push_back(Ctx::Paren);
            iv.lo = parse_expr();
            expect(Tok::Comma, "between an interval's bounds");
            iv.hi = parse_expr();
            ctx_.pop_back();
            expect(Tok::RBracket, "to close the interval");
            iv.span = Span::join(open, prev_span());
            d.bounds.push_back(std::move(iv));
            if (d.bounds.size() > size_t(limits::kMaxComponents))
                fail(d.bounds.back().span, fmt::format("more than {} intervals: iqc allows at most {} components per vector",
                                          limits::kMaxComponents, limits::kMaxComponents));
            if (accept(Tok::Cross) || (at(Tok::Word) && cur().text == "x" && peek_raw(1).kind == Tok::LBracket &&
                                       (advance(), true)))
                continue;
            break;
        }
        d.type.kind = d.bounds.size() == 1 ? TypeSpec::Scalar : TypeSpec::Vector;
        d.type.rows = int(d.bounds.size());
        d.type.span = Span::join(d.bounds.front().span, d.bounds.back().span);
    } else {
        d.type = parse_type();
        // I♥LA's attributes: `b ∈ ℤ index` (an index counting from 0) and `A ∈ ℝ^(n×n) sparse` (a storage hint:
        // the values are the same, so iqc ignores it).
        while (at(Tok::Word) && (word_is("index") || word_is("sparse"))) {
            if (word_is("index")) {
                if (d.type.kind != TypeSpec::Integer)
                    fail(word_span(), "only an integer can be an index: write 'b ∈ ℤ index'");
                d.zero_based = true;
            }
            skip_word();
        }
    }
    if (at_kw("default")) {
        Span ds = advance().span;
        expect(Tok::Eq, "after 'default'");
        colon_ends_ = true;
        d.default_value = parse_expr();
        colon_ends_ = false;
        d.default_span = Span::join(ds, d.default_value->span);
    }
    if (at(Tok::Colon)) {
        Span colon = advance().span;
        // The description is the raw text to the end of the line.
        size_t k = pos_;
        while (toks_[k].kind != Tok::Newline && toks_[k].kind != Tok::End) ++k;
        uint32_t end = toks_[k].span.begin;
        std::string_view text = sm_.text(colon.file).substr(colon.end, end - colon.end);
        while (!text.empty() && (text.front() == ' ' || text.front() == '\t')) text.remove_prefix(1);
        while (!text.empty() && (text.back() == ' ' || text.back() == '\t' || text.back() == '\r')) text.remove_suffix(1);
        d.description = std::string(text);
        pos_ = k;
    }
    d.span = Span::join(start, prev_span());
    return d;
}

// statement := NAME = expr [where decls] | NAME(params) = expr [where decls] | expr
Stmt Parser::parse_statement() {
    Stmt s;
    Span start = cur().span;
    bool assign = false, func = false;
    if (is_name_token(cur())) {
        size_t save = pos_;
        auto name = parse_name();
        if (at(Tok::Eq)) {
            assign = true;
        } else if ((at(Tok::Underscore) || at(Tok::Sub)) && !cur().space_before && indexed_assignment()) {
            return parse_indexed_assignment(name, start);
        } else if (at(Tok::LParen) && !cur().space_before) {
            // NAME ( NAME {, NAME} ) =
            size_t k = pos_ + 1;
            while (is_name_token(toks_[k])) {
                ++k;
                if (toks_[k].kind == Tok::Comma) ++k;
                else break;
            }
            func = toks_[k].kind == Tok::RParen && toks_[k + 1].kind == Tok::Eq;
        }
        if (assign || func) {
            s.name = name.first;
            s.name_span = name.second;
        } else {
            pos_ = save;
        }
    }
    if (func) {
        s.kind = StmtKind::Function;
        expect(Tok::LParen, "");
        ctx_.push_back(Ctx::Paren);
        if (!at(Tok::RParen)) s.params = parse_name_list();  // f() = …: no arguments
        ctx_.pop_back();
        expect(Tok::RParen, "to close the parameter list");
    }
    if (assign || func) {
        expect(Tok::Eq, "");
        if (assign) s.kind = StmtKind::Assign;
    } else {
        s.kind = StmtKind::Return;
    }
    s.value = parse_expr();
    s.span = Span::join(start, s.value->span);
    s.source_line = statement_text(s.span);
    if (at_kw("where") || at_kw("given")) {
        if (s.kind != StmtKind::Function)
            fail(cur().span, "a 'where' on the same line belongs to a local function definition, such as 'f(x) = x² where x ∈ ℝ'");
        advance();
        while (true) {
            s.local_decls.push_back(parse_decl());
            if (at(Tok::Comma) && (advance(), true)) continue;
            break;
        }
    }
    return s;
}

// Looks ahead from a subscript after a name: `_1 =`, `₁ =`, `_(k+1) =`.
bool Parser::indexed_assignment() {
    size_t k = pos_;
    if (toks_[k].kind == Tok::Sub) return toks_[k + 1].kind == Tok::Eq;
    ++k;  // '_'
    if (toks_[k].kind == Tok::Number) return toks_[k + 1].kind == Tok::Eq;
    if (is_name_token(toks_[k])) {  // q_i =, B_ij =, B_i,j =
        ++k;
        while (toks_[k].kind == Tok::Word && toks_[k].word.end > toks_[k].word.begin &&
               toks_[k].word.begin == toks_[k - 1].word.begin)
            ++k;
        if (toks_[k].kind == Tok::Comma && !toks_[k].space_before && is_name_token(toks_[k + 1])) k += 2;
        return toks_[k].kind == Tok::Eq;
    }
    if (toks_[k].kind != Tok::LParen) return false;
    int depth = 0;
    for (; toks_[k].kind != Tok::Newline && toks_[k].kind != Tok::End; ++k) {
        if (toks_[k].kind == Tok::LParen) ++depth;
        if (toks_[k].kind == Tok::RParen && --depth == 0) return toks_[k + 1].kind == Tok::Eq;
    }
    return false;
}

// elementwise := NAME (_ LETTER [LETTER] | _ LETTER , LETTER | _( LETTER , LETTER ) | SUBSCRIPT) = expr
//   q_i = p_i², B_ij = A_ij A_ij: the left side's subscripts are letters (a number starts a sequence).
bool Parser::elementwise_indices(Stmt& s) {
    size_t k = pos_;
    std::vector<std::pair<std::string, Span>> letters;
    auto letter = [&](const Token& t) { return t.kind == Tok::Word && letter_units(t.text).size() == 1; };
    if (toks_[k].kind == Tok::Sub) {
        if (std::isdigit(static_cast<unsigned char>(toks_[k].text[0]))) return false;
        for (size_t i = 0; i < toks_[k].text.size(); ++i) letters.push_back({toks_[k].text.substr(i, 1), toks_[k].span});
        ++k;
    } else if (k + 5 < toks_.size() && toks_[k + 1].kind == Tok::LParen && letter(toks_[k + 2]) && toks_[k + 3].kind == Tok::Comma &&
               letter(toks_[k + 4]) && toks_[k + 5].kind == Tok::RParen) {
        letters = {{toks_[k + 2].text, toks_[k + 2].span}, {toks_[k + 4].text, toks_[k + 4].span}};
        k += 6;
    } else if (letter(toks_[k + 1])) {
        letters.push_back({toks_[k + 1].text, toks_[k + 1].span});
        k += 2;
        while (letter(toks_[k]) && toks_[k].word.end > toks_[k].word.begin && toks_[k].word.begin == toks_[k - 1].word.begin)
            letters.push_back({toks_[k].text, toks_[k].span}), ++k;
        if (toks_[k].kind == Tok::Comma && !toks_[k].space_before && letter(toks_[k + 1]))
            letters.push_back({toks_[k + 1].text, toks_[k + 1].span}), k += 2;
    }
    if (letters.empty() || toks_[k].kind != Tok::Eq) return false;
    if (letters.size() > 2)
        fail(Span::join(letters.front().second, letters.back().second),
             fmt::format("an element-wise definition has one subscript (a vector or a sequence) or two (a matrix), not {}",
                         letters.size()));
    pos_ = k;
    s.elem_indices = std::move(letters);
    return true;
}

// sequence := NAME _ INDEX = expr                         (its first element, e.g. z_1 = p)
//           | NAME _ ( VAR + 1 ) = expr for VAR (∈ | = | in) lo .. hi   (the recurrence)
Stmt Parser::parse_indexed_assignment(std::pair<std::string, Span> name, Span start) {
    Stmt s;
    s.name = name.first;
    s.name_span = name.second;
    if (elementwise_indices(s)) {
        expect(Tok::Eq, "");
        s.kind = StmtKind::Assign;
        s.value = parse_expr();
        s.span = Span::join(start, s.value->span);
        if (at_kw("for"))
            fail(cur().span, fmt::format("a recurrence defines the next element from the current one: write {}_({}+1) = … "
                                         "for {} ∈ 1..N", s.name, s.elem_indices[0].first, s.elem_indices[0].first));
        s.source_line = statement_text(s.span);
        return s;
    }
    if (at(Tok::Sub)) {
        const Token& t = advance();
        s.index = make(std::isdigit(static_cast<unsigned char>(t.text[0])) ? ExprKind::Number : ExprKind::Name, t.span);
        s.index->text = t.text;
        s.index->number = std::atof(t.text.c_str());
        s.index->name_span = t.span;
    } else {
        advance();  // _
        if (at(Tok::LParen)) {
            Span open = advance().span;
            ctx_.push_back(Ctx::Paren);
            s.index = parse_expr();
            ctx_.pop_back();
            s.index->span = Span::join(open, expect(Tok::RParen, "to close the subscript").span);
        } else {
            s.index = parse_primary();
        }
    }
    expect(Tok::Eq, "");
    s.value = parse_expr();
    s.span = Span::join(start, s.value->span);
    s.kind = StmtKind::SeqInit;
    if (at_kw("for")) {
        s.kind = StmtKind::Recurrence;
        advance();
        auto var = parse_name();
        s.loop_var = var.first;
        s.loop_var_span = var.second;
        if (!(accept(Tok::In) || accept(Tok::Eq) || (at_kw("in") && (advance(), true))))
            fail(cur().span, fmt::format("expected '∈' after the index of 'for', as in 'for {} ∈ 1..8', found {}", s.loop_var, describe(cur())));
        s.range_lo = parse_expr();
        if (!accept(Tok::Ellipsis)) fail(cur().span, fmt::format("expected '..' or '…' in the range, found {}", describe(cur())));
        s.range_hi = parse_expr();
        s.span = Span::join(start, s.range_hi->span);
    }
    s.source_line = statement_text(s.span);
    return s;
}

void Parser::parse_line(Module& m) {
    if (at_kw("where") || at_kw("given")) {
        advance();
        if (at(Tok::Newline) || at(Tok::End)) return;
    }
    if (line_is_import()) {
        Stmt s;
        s.kind = StmtKind::Import;
        Span start = cur().span;
        s.imports = parse_name_list();
        advance();  // from
        if (!is_name_token(cur())) fail(cur().span, fmt::format("expected a module name after 'from', found {}", describe(cur())));
        // A module name is a file name: letters, digits and underscores written together (my_shapes2).
        s.from = cur().text;
        s.from_span = cur().span;
        advance();
        while ((is_name_token(cur()) || at(Tok::Underscore) || at(Tok::Number)) && !cur().space_before) {
            s.from += at(Tok::Underscore) ? "_" : cur().text;
            s.from_span = Span::join(s.from_span, cur().span);
            advance();
        }
        s.span = Span::join(start, s.from_span);
        m.stmts.push_back(std::move(s));
    } else if (line_is_decl()) {
        m.decls.push_back(parse_decl());
    } else {
        m.stmts.push_back(parse_statement());
    }
}

Module Parser::parse(std::string name, bool allow_header) {
    Module m;
    m.name = std::move(name);
    while (at(Tok::Newline)) advance();
    m.span = cur().span;
    if (allow_header && (at_kw("shape") || at_kw("material")) &&
        (peek_raw(1).kind == Tok::Newline || peek_raw(1).kind == Tok::End)) {
        m.kind = cur().text == "shape" ? ModuleKind::Shape : ModuleKind::Material;
        advance();
    }
    std::string first_word;
    while (!at(Tok::End)) {
        if (at(Tok::Newline) || at(Tok::Semicolon)) { advance(); continue; }
        try {
            ctx_.assign(1, Ctx::Top);
            in_condition_ = 0;
            colon_ends_ = false;
            Span start = cur().span;
            first_word = cur().text;
            const size_t stmts = m.stmts.size(), decls = m.decls.size();
            parse_line(m);
            if (!at(Tok::Newline) && !at(Tok::End) && !at(Tok::Semicolon)) {
                const Token& t = cur();
                // (the line is dropped whole: what was read of it before is not checked as a statement of its own,
                // `value_noise from noise` was "unexpected 'from'" and then four errors about `value_noise` as a value)
                m.stmts.resize(stmts);
                m.decls.resize(decls);
                if (t.kind == Tok::Unknown)
                    fail(t.span, fmt::format("unexpected character '{}'", t.text));
                if (t.kind == Tok::Eq) suggest_backticks(start, t.span);
                if (is_kw(t, "from") && t.span.file == start.file && t.span.begin > start.begin) {
                    // `value_noise from noise`: the name read as letters and a subscript
                    Diagnostic& d = diags_.error(t.span, fmt::format("unexpected {} after the end of the statement", describe(t)));
                    std::string names(diags_.sources().slice(Span{start.file, start.begin, t.span.begin}));
                    while (!names.empty() && (names.back() == ' ' || names.back() == '\t')) names.pop_back();
                    const Token& module = peek_raw(1);
                    const std::string from = module.word.end > module.word.begin ? std::string(diags_.sources().slice(module.word))
                                                                                 : module.text;
                    if (names.find(',') == std::string::npos && names.find('`') == std::string::npos && is_name_token(module))
                        Diagnostics::note(d, Span{start.file, start.begin, start.begin + uint32_t(names.size())},
                                          fmt::format("an import writes a name of several letters or with '_' in backticks: "
                                                                "`{}` from {}", names, from));
                    throw Bail{};
                }
                fail(t.span, fmt::format("unexpected {} after the end of the statement", describe(t)));
            }
        } catch (Bail&) {
            m.dropped.push_back(first_word);
            skip_line();
        }
        // Past the statement cap the rest of the module is not read (one error, not one per line).
        if (m.stmts.size() >= limits::kMaxStatements || m.decls.size() >= limits::kMaxStatements) {
            while (!at(Tok::Newline) && !at(Tok::End)) advance();
            while (at(Tok::Newline) || at(Tok::Semicolon)) advance();
            if (!at(Tok::End)) {
                try {
                    fail(cur().span, fmt::format("a module has at most {} statements and {} declarations (split it "
                                                 "into modules): the rest is not read",
                                                 limits::kMaxStatements, limits::kMaxStatements));
                } catch (Bail&) {
                }
                break;
            }
        }
    }
    return m;
}

// condition := conjunction {or conjunction}       conjunction := comparison {and comparison}
ExprPtr Parser::parse_condition() {
    limits::DepthGuard depth(depth_);
    auto conjunction = [&]() {
        ExprPtr lhs = parse_comparison();
        while (at_kw("and")) {
            nest(depth, cur().span);
            advance();
            ExprPtr rhs = parse_comparison();
            auto e = binary(BinOp::And, std::move(lhs), std::move(rhs));
            e->kind = ExprKind::Logic;
            lhs = std::move(e);
        }
        return lhs;
    };
    ExprPtr lhs = conjunction();
    while (at_kw("or")) {
        nest(depth, cur().span);
        advance();
        ExprPtr rhs = conjunction();
        auto e = binary(BinOp::Or, std::move(lhs), std::move(rhs));
        e->kind = ExprKind::Logic;
        lhs = std::move(e);
    }
    return lhs;
}

// comparison := expr (= | ≠ | < | ≤ | > | ≥) expr | expr (∈ | ∉) interval
//   interval := ([ | () expr , expr (] | ))     — closed or open at either end
ExprPtr Parser::parse_comparison() {
    if (parenthesized_condition()) {  // ( condition ): (j > 2 or j > 3) and j > 4
        Span open = advance().span;
        ctx_.push_back(Ctx::Paren);
        ExprPtr c = parse_condition();
        ctx_.pop_back();
        c->span = Span::join(open, expect(Tok::RParen, "to close the condition").span);
        return c;
    }
    ++in_condition_;
    ExprPtr c = parse_atom_comparison();
    --in_condition_;
    // x = a ± b is x = a + b or x = a - b (I♥LA: one ± per comparison).
    std::vector<Expr*> pm;
    std::function<void(Expr&)> find = [&](Expr& x) {
        if (x.kind == ExprKind::Binary && x.op == BinOp::PlusMinus) pm.push_back(&x);
        for (auto& a : x.args) find(*a);
    };
    find(*c);
    if (pm.empty()) return c;
    if (pm.size() > 1) fail(pm[1]->span, "a comparison may hold only one ±");
    // x ≠ a ± b is its negation: x is neither (it read as 'x ≠ a + b or x ≠ a - b', always true: a trial's, stop 52).
    // An order (x < a ± b) or an interval has no one reading: an error.
    const bool unequal = c->kind == ExprKind::Compare && c->op == BinOp::Neq;
    if (!(c->kind == ExprKind::Compare && (c->op == BinOp::Eq || c->op == BinOp::Neq)))
        diags_.error(pm[0]->span, "'±' in a condition takes = or ≠: x = a ± b is x = a + b or x = a - b, x ≠ a ± b is "
                                  "neither; write an order with both ends (x < a - b or x > a + b)");
    pm[0]->op = BinOp::Add;
    ExprPtr plus = clone_expr(*c);
    pm[0]->op = BinOp::Sub;
    ExprPtr minus = clone_expr(*c);
    Span whole = c->span;
    auto e = binary(unequal ? BinOp::And : BinOp::Or, std::move(plus), std::move(minus));
    e->kind = ExprKind::Logic;
    e->span = whole;
    return e;
}

// Whether the parenthesis at the current token holds a condition (a comparison, `and` or `or` directly
// inside it), not a value such as (x + 1).
bool Parser::parenthesized_condition() const {
    if (toks_[pos_].kind != Tok::LParen) return false;
    int depth = 0;
    for (size_t k = pos_; k < toks_.size() && toks_[k].kind != Tok::End; ++k) {
        Tok t = toks_[k].kind;
        if (t == Tok::LParen || t == Tok::LBracket || t == Tok::LBrace) ++depth;
        if (t == Tok::RParen || t == Tok::RBracket || t == Tok::RBrace)
            if (--depth == 0) return false;
        if (depth == 1 && (t == Tok::Eq || t == Tok::Neq || t == Tok::Lt || t == Tok::Le || t == Tok::Gt || t == Tok::Ge ||
                           t == Tok::In || t == Tok::NotIn || is_kw(toks_[k], "and") || is_kw(toks_[k], "or")))
            return true;
    }
    return false;
}

ExprPtr Parser::parse_atom_comparison() {
    ExprPtr lhs = parse_expr();
    if (at(Tok::In) || at(Tok::NotIn) || at_kw("in")) {
        bool negate = at(Tok::NotIn);
        advance();
        if (!at(Tok::LBracket) && !at(Tok::LParen))
            fail(cur().span, fmt::format("expected an interval such as [0, 1] after '∈', found {}", describe(cur())));
        bool lo_closed = at(Tok::LBracket);
        Span open = advance().span;
        ctx_.push_back(Ctx::Paren);
        ExprPtr lo = parse_expr();
        expect(Tok::Comma, "between the interval's bounds");
        ExprPtr hi = parse_expr();
        ctx_.pop_back();
        if (!at(Tok::RBracket) && !at(Tok::RParen)) {
            auto& d = diags_.error(cur().span, fmt::format("expected ']' or ')' to close the interval, found {}", describe(cur())));
            Diagnostics::note(d, open, "opened here");
            throw Bail{};
        }
        bool hi_closed = at(Tok::RBracket);
        Span close = advance().span;
        // x ∈ [a, b] is a ≤ x and x ≤ b; x ∉ [a, b] is x < a or x > b. The value is shared, not copied:
        // the checker and lowering see it twice through the Compare nodes' clones.
        auto clone = [&](const Expr& x) {
            // Comparisons need the value twice; re-parse is not possible, so build a Name-free copy by
            // wrapping: lowering evaluates both sides once each (CSE merges them).
            return clone_expr(x);
        };
        auto cmp = [&](BinOp op, ExprPtr a, ExprPtr b) {
            auto e = binary(op, std::move(a), std::move(b));
            e->kind = ExprKind::Compare;
            return e;
        };
        ExprPtr x2 = clone(*lhs);
        ExprPtr left, right;
        if (!negate) {
            left = cmp(lo_closed ? BinOp::Le : BinOp::Lt, std::move(lo), std::move(lhs));
            right = cmp(hi_closed ? BinOp::Le : BinOp::Lt, std::move(x2), std::move(hi));
        } else {
            left = cmp(lo_closed ? BinOp::Lt : BinOp::Le, std::move(lhs), std::move(lo));
            right = cmp(hi_closed ? BinOp::Gt : BinOp::Ge, std::move(x2), std::move(hi));
        }
        auto e = binary(negate ? BinOp::Or : BinOp::And, std::move(left), std::move(right));
        e->kind = ExprKind::Logic;
        e->span = Span::join(e->span, close);
        return e;
    }
    BinOp op;
    switch (cur().kind) {
        case Tok::Eq: op = BinOp::Eq; break;
        case Tok::Neq: op = BinOp::Neq; break;
        case Tok::Lt: op = BinOp::Lt; break;
        case Tok::Le: op = BinOp::Le; break;
        case Tok::Gt: op = BinOp::Gt; break;
        case Tok::Ge: op = BinOp::Ge; break;
        default: fail(cur().span, fmt::format("expected a comparison (=, ≠, <, ≤, >, ≥), found {}", describe(cur())));
    }
    advance();
    ExprPtr rhs = parse_expr();
    auto e = binary(op, std::move(lhs), std::move(rhs));
    e->kind = ExprKind::Compare;
    return e;
}

// expr := unary {(+ | -) unary}
ExprPtr Parser::parse_expr() {
    limits::DepthGuard depth(depth_);
    nest(depth, cur().span);
    ExprPtr lhs = parse_unary();
    while (true) {
        const Token& t = cur();
        if (t.kind != Tok::Plus && t.kind != Tok::Minus && t.kind != Tok::PlusMinus) break;
        // Inside a matrix, `a -b` is two items while `a - b` and `a-b` are one.
        if (ctx_.back() == Ctx::Bracket && t.space_before && !peek_raw(1).space_before) break;
        nest(depth, t.span);
        BinOp op = t.kind == Tok::Plus ? BinOp::Add : t.kind == Tok::Minus ? BinOp::Sub : BinOp::PlusMinus;
        // In a condition, `+-` written together is I♥LA's ASCII ±.
        if (op == BinOp::Add && in_condition_ && peek_raw(1).kind == Tok::Minus && !peek_raw(1).space_before) {
            op = BinOp::PlusMinus;
            advance();
        }
        advance();
        if (ctx_.back() == Ctx::Top) {  // `a +` continues on the next line, if there is one
            size_t k = pos_;
            while (toks_[k].kind == Tok::Newline) ++k;
            if (toks_[k].kind != Tok::End) pos_ = k;
        }
        ExprPtr rhs = parse_unary();
        lhs = binary(op, std::move(lhs), std::move(rhs));
    }
    return lhs;
}

// unary := (- | +) unary | mult        (so -a2 is -(2a) and -x² is -(x²))
ExprPtr Parser::parse_unary() {
    limits::DepthGuard depth(depth_);
    nest(depth, cur().span);
    if (at(Tok::Minus)) {
        Span s = advance().span;
        ExprPtr inner = parse_unary();
        auto e = make(ExprKind::Negate, Span::join(s, inner->span));
        e->args.push_back(std::move(inner));
        return e;
    }
    if (at(Tok::Plus)) {
        advance();
        return parse_unary();
    }
    return parse_mult();
}

ExprPtr Parser::parse_operand() {
    limits::DepthGuard depth(depth_);
    nest(depth, cur().span);
    if (at(Tok::Minus)) {
        Span s = advance().span;
        ExprPtr inner = parse_operand();
        auto e = make(ExprKind::Negate, Span::join(s, inner->span));
        e->args.push_back(std::move(inner));
        return e;
    }
    return parse_elem();
}

bool Parser::starts_juxtaposed_operand() {
    const Token& t = cur();
    if (ctx_.back() == Ctx::Bracket && t.space_before) return false;
    switch (t.kind) {
        case Tok::Number: case Tok::Backtick: case Tok::LParen: case Tok::LFloor: case Tok::LCeil:
        case Tok::Sqrt: case Tok::Fraction: case Tok::Norm: case Tok::DoubleBar: case Tok::Sum: case Tok::LBracket:
            return !(ctx_.back() == Ctx::Bars && (t.kind == Tok::Norm || t.kind == Tok::DoubleBar));
        case Tok::Bar: return ctx_.back() != Ctx::Bars;
        case Tok::Word: return !is_keyword(t.text) || t.text == "sum";
        case Tok::LAngle: return true;
        case Tok::Lt: return in_condition_ == 0 && ascii_inner_ahead();  // 2<u, v> outside conditions
        default: return false;
    }
}

// mult := elem {(⋅ | * | / | ÷) operand | elem}      (juxtaposition; a/bc is (a/b)c)
ExprPtr Parser::parse_mult() {
    limits::DepthGuard depth(depth_);
    ExprPtr lhs = parse_elem();
    while (true) {
        BinOp op;
        const Token& t = cur();
        if (t.kind == Tok::Dot) op = BinOp::Dot;
        else if (t.kind == Tok::Star) op = BinOp::Star;
        else if (t.kind == Tok::Slash || t.kind == Tok::Divide) op = BinOp::Div;
        else if (starts_juxtaposed_operand()) op = BinOp::Juxtapose;
        else break;
        nest(depth, t.span);
        if (op != BinOp::Juxtapose) advance();
        ExprPtr rhs = op == BinOp::Juxtapose ? parse_elem() : parse_operand();
        lhs = binary(op, std::move(lhs), std::move(rhs));
    }
    return lhs;
}

// elem := power {(∘ | × | ⊗ | \ | :) power}      (I♥LA's product operators between factors)
ExprPtr Parser::parse_elem() {
    limits::DepthGuard depth(depth_);
    ExprPtr lhs = parse_power();
    while (true) {
        BinOp op;
        if (at(Tok::Circle)) op = BinOp::Hadamard;
        else if (at(Tok::Cross)) op = BinOp::Cross;
        else if (at(Tok::Kronecker)) op = BinOp::Kronecker;
        else if (at(Tok::Backslash)) op = BinOp::Solve;
        else if (at(Tok::Colon) && !colon_ends_) op = BinOp::Frobenius;
        else break;
        nest(depth, cur().span);
        advance();
        ExprPtr rhs = parse_power();
        lhs = binary(op, std::move(lhs), std::move(rhs));
    }
    return lhs;
}

// power := postfix {^ [-] primary | SUPERSCRIPT}      (x^2y is x²·y; ᵀ and ⁻¹ are superscripts too)
ExprPtr Parser::parse_power() {
    limits::DepthGuard depth(depth_);
    ExprPtr base = parse_postfix();
    while (true) {
        if (at(Tok::Super) && !cur().space_before) {
            nest(depth, cur().span);
            const Token& t = advance();
            if (t.text == "T") {
                auto e = make(ExprKind::Transpose, Span::join(base->span, t.span));
                e->args.push_back(std::move(base));
                base = std::move(e);
                continue;
            }
            if (t.text == "+")
                fail(t.span, "the pseudo-inverse A⁺ is not supported (it needs a singular value decomposition); for an "
                             "invertible matrix write A⁻¹");
            if (t.text.empty() || t.text.find_first_not_of("+-0123456789") != std::string::npos ||
                t.text.find_first_of("0123456789") == std::string::npos)
                fail(t.span, "a superscript power must be an integer such as ² or ⁻¹");
            // One integer: a sign only in front (⁻¹⁻¹ would read as -1 and drop the rest; x⁻¹⁻¹ is (x⁻¹)⁻¹ or x⁻²?).
            if (t.text.find_first_of("+-", 1) != std::string::npos)
                fail(t.span, fmt::format("a superscript power is one integer such as ² or ⁻¹, not '{}': write the powers "
                                         "apart with parentheses, (x⁻¹)⁻¹, or as one power, x^(-1-1)",
                                         std::string(sm_.slice(t.span))));
            auto ex = make(ExprKind::Number, t.span);
            ex->number = literal_value(t);
            ex->text = t.text;
            auto e = make(ExprKind::Power, Span::join(base->span, t.span));
            e->args.push_back(std::move(base));
            e->args.push_back(std::move(ex));
            base = std::move(e);
            continue;
        }
        if (at(Tok::Caret)) {
            nest(depth, cur().span);
            advance();
            if (at(Tok::Word) && cur().text == "T" && !known_.count("T")) {
                Span ts = advance().span;
                auto e = make(ExprKind::Transpose, Span::join(base->span, ts));
                e->args.push_back(std::move(base));
                base = std::move(e);
                continue;
            }
            ExprPtr ex;
            if (at(Tok::Minus)) {
                Span s = advance().span;
                ExprPtr inner = parse_postfix(true);
                ex = make(ExprKind::Negate, Span::join(s, inner->span));
                ex->args.push_back(std::move(inner));
            } else {
                ex = parse_postfix(true);
            }
            auto e = make(ExprKind::Power, Span::join(base->span, ex->span));
            e->args.push_back(std::move(base));
            e->args.push_back(std::move(ex));
            base = std::move(e);
            continue;
        }
        break;
    }
    return base;
}

// postfix := primary {_ index [, index] | SUBSCRIPT | (args)}
// In an exponent, a one-letter value is not called: x^α(1, 2) is x^α · (1, 2), but e^f(x) calls f.
ExprPtr Parser::parse_postfix(bool exponent) {
    limits::DepthGuard depth(depth_);
    ExprPtr e = parse_primary();
    while (true) {
        if (e->kind == ExprKind::Name && (function_power(e) || log_base(e))) continue;
        if (e->kind == ExprKind::Number && (e->text == "0" || e->text == "1" || e->text == "𝟙") &&
            (at(Tok::Sub) || at(Tok::Underscore)) && !cur().space_before) {
            e = parse_sized_block(std::move(e));
            continue;
        }
        if ((e->kind == ExprKind::Norm || e->kind == ExprKind::Abs) && e->args.size() == 1 && e->text.empty()) {
            if ((at(Tok::Sub) || (at(Tok::Underscore) && !cur().space_before))) {
                parse_norm_subscript(*e);
                continue;
            }
            // ‖A‖²_F, ‖v‖^2_2: I♥LA lets the power come before the subscript.
            size_t k = pos_;
            bool sup = toks_[k].kind == Tok::Super && !toks_[k].space_before && toks_[k].text.find_first_not_of("0123456789") == std::string::npos;
            bool caret = toks_[k].kind == Tok::Caret && toks_[k + 1].kind == Tok::Number;
            size_t after = k + (sup ? 1 : caret ? 2 : 0);
            if ((sup || caret) && (toks_[after].kind == Tok::Sub || toks_[after].kind == Tok::Underscore) &&
                !toks_[after].space_before) {
                const Token& pw = toks_[after - 1];
                auto ex = make(ExprKind::Number, pw.span);
                ex->number = literal_value(pw);
                ex->text = pw.text;
                pos_ = after;
                parse_norm_subscript(*e);
                auto power = make(ExprKind::Power, Span::join(e->span, ex->span));
                power->args.push_back(std::move(e));
                power->args.push_back(std::move(ex));
                e = std::move(power);
                continue;
            }
        }
        if (at(Tok::Sub)) {
            nest(depth, cur().span);
            const Token& t = advance();
            auto idx = make(ExprKind::Index, Span::join(e->span, t.span));
            IndexItem it;
            if (std::isdigit(static_cast<unsigned char>(t.text[0]))) {
                it.expr = make(ExprKind::Number, t.span);
                it.expr->number = std::atof(t.text.c_str());
                it.expr->text = t.text;
            } else {
                it.expr = make(ExprKind::Name, t.span);
                it.expr->text = t.text;
                it.expr->name_span = t.span;
            }
            it.span = t.span;
            idx->args.push_back(std::move(e));
            idx->indices.push_back(std::move(it));
            e = std::move(idx);
            continue;
        }
        if (at(Tok::Underscore) && !cur().space_before) {
            if (e->kind == ExprKind::Name && peek_raw(1).kind == Tok::LParen &&
                (e->text == "min" || e->text == "max" || sm_.slice(e->word_span) == "argmin" || sm_.slice(e->word_span) == "argmax"))
                fail(e->word_span.end > e->word_span.begin ? e->word_span : e->span,
                     "I♥LA's optimization (min_(x ∈ …), argmin_(x ∈ …)) is not supported: iqc compiles closed-form math");
            nest(depth, cur().span);
            advance();
            auto idx = make(ExprKind::Index, e->span);
            idx->args.push_back(std::move(e));
            auto push = [&](IndexItem it) {
                idx->span = Span::join(idx->span, it.span);
                idx->indices.push_back(std::move(it));
            };
            auto parse_index = [&]() {
                IndexItem it;
                const Token& t = cur();
                it.span = t.span;
                if (t.kind == Tok::Star) {
                    advance();
                } else if (t.kind == Tok::Number) {
                    it.expr = make(ExprKind::Number, t.span);
                    it.expr->number = std::atof(t.text.c_str());
                    it.expr->text = t.text;
                    advance();
                } else if (is_name_token(t)) {
                    it.expr = make(ExprKind::Name, t.span);
                    it.expr->text = t.text;
                    it.expr->name_span = t.span;
                    advance();
                } else if (t.kind == Tok::LParen) {
                    // _(i), _(k+1), _(2,3), _(i,*): one or two subscripts
                    advance();
                    ctx_.push_back(Ctx::Paren);
                    for (bool first = true;; first = false) {
                        IndexItem item;
                        item.span = cur().span;
                        if (at(Tok::Star)) advance();
                        else item.expr = parse_expr(), item.span = item.expr->span;
                        if (!accept(Tok::Comma)) {
                            ctx_.pop_back();
                            Span close = expect(Tok::RParen, "to close the subscript").span;
                            if (first) item.span = Span::join(t.span, close);  // _(k+1): the whole parenthesis
                            push(std::move(item));
                            idx->span = Span::join(idx->span, close);
                            return;
                        }
                        push(std::move(item));
                    }
                } else {
                    fail(t.span, fmt::format("expected a subscript after '_', found {}", describe(t)));
                }
                push(std::move(it));
            };
            parse_index();
            // A second subscript written against its comma (`A_2,3`, `A_i,j`, `A_i,*`) belongs to the name, in
            // any context (I♥LA); `(p_1, p_2)` and `(p_1,p_2)` stay two items.
            while (toks_[pos_].kind == Tok::Comma && !toks_[pos_].space_before && !peek_raw(1).space_before) {
                const Token& n = peek_raw(1);
                const Token& after = peek_raw(2);
                bool index = n.kind == Tok::Number || n.kind == Tok::Star ||
                             (is_name_token(n) && !((after.kind == Tok::Underscore || after.kind == Tok::Sub ||
                                                     after.kind == Tok::LParen) && !after.space_before));
                if (!index || idx->indices.size() >= 3) break;  // A_i,2,3: an entry of a sequence's matrix
                advance();
                parse_index();
            }
            // A_ij: two one-letter subscripts written together (a word split into letters).
            while (idx->indices.size() == 1 && idx->indices[0].expr && idx->indices[0].expr->kind == ExprKind::Name &&
                   pos_ > 0 && toks_[pos_ - 1].word.end > toks_[pos_ - 1].word.begin && is_name_token(toks_[pos_]) &&
                   toks_[pos_].word.begin == toks_[pos_ - 1].word.begin && toks_[pos_].word.end == toks_[pos_ - 1].word.end)
                parse_index();
            e = std::move(idx);
            continue;
        }
        bool callable = !exponent || functions_.count(e->text) || letter_units(e->text).size() > 1;
        if (at(Tok::LParen) && !cur().space_before && e->kind == ExprKind::Name && callable) {
            e = parse_call(std::move(e));
            continue;
        }
        break;
    }
    return e;
}

// call := NAME ( [expr {, expr}] )
ExprPtr Parser::parse_call(ExprPtr callee) {
    limits::DepthGuard depth(depth_);
    nest(depth, cur().span);
    advance();  // (
    ctx_.push_back(Ctx::Paren);
    auto call = make(ExprKind::Call, callee->span);
    call->text = callee->text;
    call->name_span = callee->name_span;
    call->word_span = callee->word_span;
    if (!at(Tok::RParen)) {
        call->args.push_back(parse_expr());
        while (accept(Tok::Comma)) call->args.push_back(parse_expr());
    }
    ctx_.pop_back();
    Span close = expect(Tok::RParen, "to close the argument list").span;
    call->span = Span::join(call->span, close);
    return call;
}

// function_power := TRIG (SUPERSCRIPT | ^ INTEGER) ( args )      sin²(x) is (sin x)², as in I♥LA
bool Parser::function_power(ExprPtr& e) {
    if (!is_power_function(e->text)) return false;
    size_t k = pos_;
    std::string power;
    Span power_span = toks_[k].span;
    if (toks_[k].kind == Tok::Super && !toks_[k].space_before) {
        power = toks_[k].text;
        ++k;
    } else if (toks_[k].kind == Tok::Caret) {
        ++k;
        if (toks_[k].kind == Tok::Minus) power = "-", ++k;
        if (toks_[k].kind != Tok::Number) return false;
        power += toks_[k].text;
        power_span = Span::join(power_span, toks_[k].span);
        ++k;
    } else {
        return false;
    }
    if (toks_[k].kind != Tok::LParen) return false;
    if (power.empty() || power.find_first_not_of("0123456789") != std::string::npos) {
        auto& d = diags_.error(power_span, fmt::format("'{}' with the power {} is ambiguous", e->text, power));
        Diagnostics::note(d, e->span, power == "-1" ? fmt::format("for the inverse function write a{}(x) or arc{}(x); for "
                                                                  "1/{}(x) write {}(x)⁻¹", e->text, e->text, e->text, e->text)
                                                    : std::string("a function's power must be a whole number such as ² "
                                                                  "(sin²(x) is sin(x)²)"));
        throw Bail{};
    }
    pos_ = k;
    auto ex = make(ExprKind::Number, power_span);
    ex->number = std::strtod(power.c_str(), nullptr);
    ex->text = power;
    ExprPtr call = parse_call(std::move(e));
    auto p = make(ExprKind::Power, call->span);
    p->args.push_back(std::move(call));
    p->args.push_back(std::move(ex));
    e = std::move(p);
    return true;
}

// log_base := log (_2 | _10 | ₂ | ₁₀) ( expr )     the logarithm to base 2 or 10
bool Parser::log_base(ExprPtr& e) {
    if (e->text != "log") return false;
    size_t k = pos_;
    std::string base;
    if (toks_[k].kind == Tok::Sub && !toks_[k].space_before) {
        base = toks_[k].text, ++k;
    } else if (toks_[k].kind == Tok::Underscore && !toks_[k].space_before && toks_[k + 1].kind == Tok::Number) {
        base = toks_[k + 1].text, k += 2;
    } else {
        return false;
    }
    if (toks_[k].kind != Tok::LParen || (base != "2" && base != "10")) return false;
    Span s = Span::join(e->span, toks_[k - 1].span);
    pos_ = k;
    e->text = "log_" + base;
    e->span = e->name_span = s;
    e = parse_call(std::move(e));
    return true;
}

ExprPtr Parser::parse_delimited(ExprKind kind, Tok close, Span open, const char* what) {
    ctx_.push_back(kind == ExprKind::Norm || kind == ExprKind::Abs ? Ctx::Bars : Ctx::Paren);
    ExprPtr inner = parse_expr();
    ctx_.pop_back();
    // `|y||` closing two absolute values at once (`||x| + |y||`): the first bar closes this one.
    if (close == Tok::Bar && at(Tok::DoubleBar)) split_double_bar();
    if (!at(close)) {
        if (kind == ExprKind::Norm && at(Tok::DoubleBar)) {
        } else {
            auto& d = diags_.error(cur().span, fmt::format("expected {} to close {}, found {}", token_description(close),
                                                           what, describe(cur())));
            Diagnostics::note(d, open, "opened here");
            throw Bail{};
        }
    }
    Span end = advance().span;
    auto e = make(kind, Span::join(open, end));
    e->args.push_back(std::move(inner));
    return e;
}

// matrix := [ row {(; | newline) row} ]       row := item {[,] item}
ExprPtr Parser::parse_matrix(Span open) {
    ctx_.push_back(Ctx::Bracket);
    auto m = make(ExprKind::Matrix, open);
    std::vector<ExprPtr> row;
    auto end_row = [&]() {
        if (!row.empty()) m->rows.push_back(std::move(row));
        row.clear();
    };
    while (true) {
        const Token& t = cur();
        if (t.kind == Tok::RBracket) break;
        if (t.kind == Tok::End) {
            auto& d = diags_.error(t.span, "expected ']' to close the matrix");
            Diagnostics::note(d, open, "opened here");
            throw Bail{};
        }
        if (t.kind == Tok::Newline || t.kind == Tok::Semicolon) { advance(); end_row(); continue; }
        if (t.kind == Tok::Comma) { advance(); continue; }
        // A new statement (`y = …`) inside an unclosed matrix: report the bracket, not the `=`.
        if (t.kind == Tok::Eq || (t.line_start && is_name_token(t) && peek_raw(1).kind == Tok::Eq) || at_kw("where")) {
            auto& d = diags_.error(t.span, fmt::format("expected ']' to close the matrix, found {}", describe(t)));
            Diagnostics::note(d, open, "opened here");
            throw Bail{};
        }
        row.push_back(parse_expr());
    }
    end_row();
    ctx_.pop_back();
    m->span = Span::join(open, advance().span);
    if (m->rows.empty()) fail(m->span, "a matrix needs at least one entry");
    return m;
}

// sum := (∑ | sum) (_ NAME | SUBSCRIPT | _( NAME [for condition] )) term
//   ∑_i a_i b_i + c is (∑_i a_i b_i) + c: the summand is one multiplicative term.
//   ∑_(j for j ≠ i) x_j adds only the terms whose index satisfies the condition.
ExprPtr Parser::parse_sum(Span start) {
    std::string index;
    ExprPtr condition;
    if (at(Tok::Sub) && !cur().space_before) {
        index = advance().text;
    } else if (at(Tok::Underscore) && !cur().space_before) {
        advance();
        if (at(Tok::LParen)) {
            Span open = advance().span;
            ctx_.push_back(Ctx::Paren);
            if (!is_name_token(cur()))
                fail(cur().span, fmt::format("expected the summation index after '∑_(', found {}", describe(cur())));
            index = advance().text;
            if (at(Tok::Comma) || at(Tok::In) || at_kw("in"))
                fail(cur().span, "a sum over the members of a set (∑_(i,j ∈ E)) is not supported: sets are not part of "
                                 "iqc's language");
            if (at_kw("for")) {
                advance();
                condition = parse_condition();
            }
            ctx_.pop_back();
            if (!at(Tok::RParen)) {
                auto& d = diags_.error(cur().span, fmt::format("expected ')' to close the sum's index, found {}", describe(cur())));
                Diagnostics::note(d, open, "opened here");
                throw Bail{};
            }
            advance();
        } else if (is_name_token(cur())) {
            index = advance().text;
        } else {
            fail(cur().span, fmt::format("expected the summation index after '∑_', found {}", describe(cur())));
        }
    } else {
        fail(cur().span, "expected a summation index, as in ∑_i v_i");
    }
    ExprPtr body = parse_mult();
    auto e = make(ExprKind::Sum, Span::join(start, body->span));
    e->text = index;
    e->args.push_back(std::move(body));
    if (condition) e->args.push_back(std::move(condition));
    return e;
}

// sized_block := (0 | 1 | 𝟙) (_ size [, size] | _( size [(, | × | x) size] ) | SUBSCRIPT [, SUBSCRIPT])
//   size := INTEGER | NAME          0_2,3 is a 2×3 zero matrix, 1_n a vector of n ones
ExprPtr Parser::parse_sized_block(ExprPtr symbol) {
    auto e = make(ExprKind::Block, symbol->span);
    e->text = symbol->text == "0" ? "0" : "1";
    auto size = [&](const Token& t) {
        IndexItem it;
        it.span = t.span;
        if (t.kind == Tok::Number || t.kind == Tok::Sub) {
            it.expr = make(ExprKind::Number, t.span);
            it.expr->number = std::atof(t.text.c_str());
            it.expr->text = t.text;
            if (t.kind == Tok::Sub && !std::isdigit(static_cast<unsigned char>(t.text[0]))) it.expr->kind = ExprKind::Name;
        } else if (is_name_token(t)) {
            it.expr = make(ExprKind::Name, t.span);
            it.expr->text = t.text;
            it.expr->name_span = t.span;
        } else {
            fail(t.span, fmt::format("expected the size of the {} block ({}_2,3 or {}_n), found {}", e->text == "0" ? "zero" : "ones",
                                     symbol->text, symbol->text, describe(t)));
        }
        e->span = Span::join(e->span, t.span);
        e->indices.push_back(std::move(it));
        advance();
    };
    if (at(Tok::Sub)) {
        size(cur());
        if (at(Tok::Comma) && !cur().space_before && peek_raw(1).kind == Tok::Sub) advance(), size(cur());
        return e;
    }
    advance();  // _
    if (at(Tok::LParen)) {
        advance();
        size(cur());
        if (accept(Tok::Comma) || accept(Tok::Cross) || (at(Tok::Word) && cur().text == "x" && (advance(), true))) size(cur());
        e->span = Span::join(e->span, expect(Tok::RParen, "to close the block's size").span);
        return e;
    }
    size(cur());
    if (at(Tok::Comma) && !cur().space_before && !peek_raw(1).space_before &&
        (peek_raw(1).kind == Tok::Number || is_name_token(peek_raw(1))))
        advance(), size(cur());
    return e;
}

// At a `||` that opens an operand: whether it opens two absolute values (`||x| - a|`) rather than a norm
// (`||x||`, the ASCII ‖): the first bar after it outside brackets and ‖…‖ decides, a `||` for the norm, a `|`
// for two absolute values. Undecided (the line ends) is a norm, whose error says what closes it.
bool Parser::double_bar_opens_abs() const {
    int depth = 0;
    bool in_norm = false;
    for (size_t k = pos_ + 1; k < toks_.size(); ++k) {
        switch (toks_[k].kind) {
            case Tok::LParen: case Tok::LBracket: case Tok::LBrace: case Tok::LFloor: case Tok::LCeil: ++depth; break;
            case Tok::RParen: case Tok::RBracket: case Tok::RBrace: case Tok::RFloor: case Tok::RCeil:
                if (--depth < 0) return false;
                break;
            case Tok::Norm: in_norm = !in_norm; break;
            case Tok::DoubleBar: if (depth == 0 && !in_norm) return false; break;
            case Tok::Bar: if (depth == 0 && !in_norm) return true; break;
            case Tok::Newline: case Tok::End: case Tok::Eq: return false;
            default: break;
        }
    }
    return false;
}

// Splits the `||` at the cursor into two `|` tokens, one byte each.
void Parser::split_double_bar() {
    Token first = toks_[pos_], second = toks_[pos_];
    first.kind = second.kind = Tok::Bar;
    first.span.end = first.span.begin + 1;
    second.span.begin = first.span.end;
    second.space_before = false;
    second.line_start = false;
    toks_[pos_] = first;
    toks_.insert(toks_.begin() + std::ptrdiff_t(pos_) + 1, second);
}

// Whether the `<` at the current token opens <u, v>: a comma and then a `>` follow on the line, outside
// any bracket opened after the `<`.
bool Parser::ascii_inner_ahead() const {
    int depth = 0;
    bool comma = false;
    for (size_t k = pos_ + 1; k < toks_.size(); ++k) {
        Tok t = toks_[k].kind;
        if (t == Tok::Newline || t == Tok::End || t == Tok::Eq || t == Tok::Lt || t == Tok::Semicolon) return false;
        if (t == Tok::LParen || t == Tok::LBracket || t == Tok::LAngle) ++depth;
        if (t == Tok::RParen || t == Tok::RBracket || t == Tok::RAngle) --depth;
        if (depth < 0) return false;
        if (depth == 0 && t == Tok::Comma) comma = true;
        if (depth == 0 && t == Tok::Gt) return comma;
    }
    return false;
}

// inner := ⟨ expr , expr ⟩ [_ NAME] | < expr , expr > [_ NAME]     ⟨u, v⟩_M is vᵀ M u
ExprPtr Parser::parse_inner(const Token& open_tok) {
    bool angle = open_tok.kind == Tok::LAngle;
    Span open = open_tok.span;
    ctx_.push_back(Ctx::Paren);
    ++in_condition_;  // `>` closes: no comparison or `<u, v>` inside
    ExprPtr a = parse_expr();
    --in_condition_;
    if (!at(Tok::Comma)) {
        auto& d = diags_.error(cur().span, fmt::format("expected ',' between the two vectors of the inner product, found {}",
                                                       describe(cur())));
        Diagnostics::note(d, open, angle ? "the inner product ⟨u, v⟩ opens here" : "'<' here opens an inner product <u, v>");
        throw Bail{};
    }
    advance();
    ++in_condition_;
    ExprPtr b = parse_expr();
    --in_condition_;
    ctx_.pop_back();
    if (!at(angle ? Tok::RAngle : Tok::Gt)) {
        auto& d = diags_.error(cur().span, fmt::format("expected {} to close the inner product, found {}",
                                                       angle ? "'⟩'" : "'>'", describe(cur())));
        Diagnostics::note(d, open, "opened here");
        throw Bail{};
    }
    auto e = make(ExprKind::Inner, Span::join(open, advance().span));
    e->args.push_back(std::move(a));
    e->args.push_back(std::move(b));
    if (at(Tok::Underscore) && !cur().space_before && is_name_token(peek_raw(1))) {
        advance();
        auto m = make(ExprKind::Name, cur().span);
        auto [n, sp] = parse_name();
        m->text = n;
        m->name_span = sp;
        e->span = Span::join(e->span, sp);
        e->args.push_back(std::move(m));
    }
    return e;
}

// norm_subscript := _ (INTEGER | ∞ | * | NAME | ( expr )) | SUBSCRIPT     ‖v‖_1, ‖v‖_∞, ‖A‖_F, ‖v‖_p, ‖v‖₁
void Parser::parse_norm_subscript(Expr& norm) {
    limits::DepthGuard depth(depth_);
    nest(depth, cur().span);
    if (at(Tok::Sub)) {
        const Token& t = advance();
        auto n = make(ExprKind::Number, t.span);
        n->number = std::atof(t.text.c_str());
        n->text = t.text;
        if (!std::isdigit(static_cast<unsigned char>(t.text[0]))) {
            n->kind = ExprKind::Name;
            n->name_span = t.span;
        }
        norm.args.push_back(std::move(n));
        norm.span = Span::join(norm.span, t.span);
        return;
    }
    advance();  // _
    const Token& t = cur();
    if (t.kind == Tok::Infinity || t.kind == Tok::Star || (t.kind == Tok::Word && t.text == "F" && !known_.count("F"))) {
        norm.text = t.kind == Tok::Infinity ? "∞" : t.kind == Tok::Star ? "*" : "F";
        norm.span = Span::join(norm.span, advance().span);
        return;
    }
    ExprPtr sub;
    if (t.kind == Tok::Number) {
        sub = make(ExprKind::Number, t.span);
        sub->number = std::strtod(t.text.c_str(), nullptr);
        sub->text = t.text;
        advance();
    } else if (is_name_token(t)) {
        sub = make(ExprKind::Name, t.span);
        auto [n, sp] = parse_name();
        sub->text = n;
        sub->name_span = sp;
    } else if (t.kind == Tok::LParen) {
        advance();
        ctx_.push_back(Ctx::Paren);
        if (at(Tok::Infinity) || at(Tok::Star)) {
            norm.text = at(Tok::Infinity) ? "∞" : "*";
            advance();
        } else {
            sub = parse_expr();
        }
        ctx_.pop_back();
        Span close = expect(Tok::RParen, "to close the norm's subscript").span;
        norm.span = Span::join(norm.span, close);
        if (!sub) return;
    } else {
        fail(t.span, fmt::format("expected the norm's subscript (1, 2, ∞, F, a number or a name) after '_', found {}",
                                 describe(t)));
    }
    norm.span = Span::join(norm.span, sub->span);
    norm.args.push_back(std::move(sub));
}

// sequence_literal := { expr {, expr} }      (after the first item; iqc's value of a sequence x_i ∈ ℝ³)
ExprPtr Parser::parse_sequence_literal(Span open, ExprPtr first) {
    ctx_.back() = Ctx::Paren;
    auto e = make(ExprKind::Sequence, open);
    e->args.push_back(std::move(first));
    while (accept(Tok::Comma)) e->args.push_back(parse_expr());
    ctx_.pop_back();
    if (!at(Tok::RBrace)) {
        auto& d = diags_.error(cur().span, fmt::format("expected '}}' to close the sequence, found {}", describe(cur())));
        Diagnostics::note(d, open, "opened here");
        throw Bail{};
    }
    e->span = Span::join(open, advance().span);
    return e;
}

// piecewise := { case {newline case}      case := expr [,] (if condition | otherwise)
ExprPtr Parser::parse_piecewise(Span open) {
    ctx_.push_back(Ctx::Brace);
    auto p = make(ExprKind::Piecewise, open);
    // `{}`: an empty sequence (`--set 'x={}'` said "a piecewise definition needs at least one 'if' case").
    // Said, and read as an empty sequence: the declaration stands (its uses are not 'undefined', a trial's cascade).
    if (at(Tok::RBrace)) {
        diags_.error(Span::join(open, cur().span), "'{}' is an empty sequence: a sequence has at least one element, as in {1, 2}");
        ctx_.pop_back();
        auto e = make(ExprKind::Sequence, open);
        e->span = Span::join(open, advance().span);
        return e;
    }
    while (true) {
        while (at(Tok::Newline)) advance();
        if (at(Tok::RBrace)) { advance(); break; }
        ExprPtr value = parse_expr();
        // {a, b, c}: a sequence literal (a comma not followed by `if`/`otherwise`, or a `}` after one item).
        if (p->rows.empty() && (at(Tok::RBrace) || (at(Tok::Comma) && !is_kw(peek_raw(1), "if") &&
                                                    !is_kw(peek_raw(1), "otherwise"))))
            return parse_sequence_literal(open, std::move(value));
        accept(Tok::Comma);
        if (at_kw("otherwise")) {
            p->span = Span::join(p->span, advance().span);
            p->otherwise = std::move(value);
            accept(Tok::RBrace);
            break;
        }
        if (!at_kw("if")) fail(cur().span, fmt::format("expected 'if' or 'otherwise' in the piecewise case, found {}", describe(cur())));
        advance();
        ExprPtr cond = parse_condition();
        p->span = Span::join(p->span, cond->span);
        std::vector<ExprPtr> c;
        c.push_back(std::move(value));
        c.push_back(std::move(cond));
        p->rows.push_back(std::move(c));
        // The cases continue on the next line only if it holds another case.
        size_t k = pos_;
        while (toks_[k].kind == Tok::Newline) ++k;
        bool more = false;
        for (size_t j = k; toks_[j].kind != Tok::Newline && toks_[j].kind != Tok::End; ++j)
            if (is_kw(toks_[j], "if") || is_kw(toks_[j], "otherwise") || toks_[j].kind == Tok::RBrace) more = true;
        if (!more) break;
    }
    ctx_.pop_back();
    if (p->rows.empty()) fail(p->span, "a piecewise definition needs at least one 'if' case");
    return p;
}

// primary := NUMBER | NAME | FRACTION | ( expr {, expr} ) | [ matrix ] | ‖expr‖ | |expr| | ⌊expr⌋ | ⌈expr⌉
//          | √ postfix | { piecewise
ExprPtr Parser::parse_primary() {
    limits::DepthGuard depth(depth_);
    nest(depth, cur().span);
    const Token& t = cur();
    switch (t.kind) {
        case Tok::Number: {
            auto e = make(ExprKind::Number, t.span);
            e->number = t.text == "𝟙" ? 1.0 : literal_value(t);
            e->text = t.text;
            advance();
            // `1.2.3` lexes as 1.2 then .3, which juxtaposition would multiply (0.36), and `1e5.5` as 1e5 then .5: a
            // number written straight after a number is a typo, not a product (a new user's trial).
            if (at(Tok::Number) && !cur().space_before && !cur().text.empty() && cur().text[0] == '.')
                fail(Span{e->span.file, e->span.begin, cur().span.end},
                     fmt::format("'{}{}' is not a number: a second decimal point (write a space for a product)", e->text, cur().text));
            if (e->text == "𝟙" && !((at(Tok::Sub) || at(Tok::Underscore)) && !cur().space_before))
                fail(e->span, "𝟙 needs its size, as in 𝟙_3 (a vector of ones) or 𝟙_2,3 (a matrix of ones)");
            return e;
        }
        case Tok::Fraction: {
            auto e = make(ExprKind::Number, t.span);
            int num = t.text[0] - '0', den = t.text[2] - '0';
            e->number = double(num) / double(den);
            e->text = t.text;
            advance();
            return e;
        }
        case Tok::Word:
        case Tok::Backtick: {
            if (t.kind == Tok::Word && t.text == "sum") {  // I♥LA's ASCII ∑
                Span s = advance().span;
                if (!(at(Tok::Underscore) || at(Tok::Sub)) || cur().space_before)
                    fail(s, "'sum' is I♥LA's ∑ and needs its index, as in sum_i x_i");
                return parse_sum(s);
            }
            if (t.kind == Tok::Word && is_keyword(t.text))
                fail(t.span, fmt::format("unexpected keyword '{}' in an expression", t.text));
            auto e = make(ExprKind::Name, t.span);
            e->word_span = t.word;
            auto [n, s] = parse_name();
            e->text = n;
            e->span = s;
            e->name_span = s;
            return e;
        }
        case Tok::LParen: {
            Span open = advance().span;
            ctx_.push_back(Ctx::Paren);
            std::vector<ExprPtr> items;
            items.push_back(parse_expr());
            while (accept(Tok::Comma)) items.push_back(parse_expr());
            ctx_.pop_back();
            if (!at(Tok::RParen)) {
                auto& d = diags_.error(cur().span, fmt::format("expected ')', found {}", describe(cur())));
                Diagnostics::note(d, open, "opened here");
                throw Bail{};
            }
            Span close = advance().span;
            if (items.size() == 1) {
                items[0]->span = Span::join(open, close);
                return std::move(items[0]);
            }
            auto e = make(ExprKind::Vector, Span::join(open, close));
            e->args = std::move(items);
            return e;
        }
        case Tok::LBracket: return parse_matrix(advance().span);
        case Tok::LBrace: return parse_piecewise(advance().span);
        case Tok::LAngle: return parse_inner(advance());
        case Tok::Lt:
            if (ascii_inner_ahead()) return parse_inner(advance());
            fail(t.span, fmt::format("expected an expression, found {}", describe(t)));
        case Tok::Norm: return parse_delimited(ExprKind::Norm, Tok::Norm, advance().span, "the norm");
        case Tok::DoubleBar:
            // `||‖p‖ - 0.6| - 0.1|` (Quilez's onion): two absolute values opened at once, not a norm.
            if (double_bar_opens_abs()) {
                split_double_bar();
                return parse_delimited(ExprKind::Abs, Tok::Bar, advance().span, "the absolute value");
            }
            return parse_delimited(ExprKind::Norm, Tok::DoubleBar, advance().span, "the norm");
        case Tok::Bar: return parse_delimited(ExprKind::Abs, Tok::Bar, advance().span, "the absolute value");
        case Tok::LFloor: return parse_delimited(ExprKind::Floor, Tok::RFloor, advance().span, "the floor");
        case Tok::LCeil: return parse_delimited(ExprKind::Ceil, Tok::RCeil, advance().span, "the ceiling");
        case Tok::Sum: return parse_sum(advance().span);
        case Tok::Sqrt: {
            Span s = advance().span;
            ExprPtr inner = parse_postfix();
            auto e = make(ExprKind::Sqrt, Span::join(s, inner->span));
            e->args.push_back(std::move(inner));
            return e;
        }
        case Tok::Unknown:
            if (t.text == "∂")
                fail(t.span, "I♥LA's derivatives (∂) are not supported: write the derivative out (iqc differentiates "
                             "shapes itself for their normals)");
            if (t.text == "∫") fail(t.span, "I♥LA's integrals (∫) are not supported: iqc's math has closed forms only");
            if (t.text == "``") fail(t.span, "a name between backticks cannot be empty");
            fail(t.span, fmt::format("unexpected character '{}'", t.text));
        case Tok::Newline:
        case Tok::End: fail(t.span, "expected an expression, found the end of the line");
        default: fail(t.span, fmt::format("expected an expression, found {}", describe(t)));
    }
}

}  // namespace

ast::Module parse_module(const SourceManager& sm, FileId file, const std::vector<TextRange>& ranges,
                         std::string name, const ParseOptions& opts, Diagnostics& diags) {
    std::vector<Token> raw = lex(sm, file, ranges);
    std::set<std::string> known = prescan(raw);
    WordSplitter own(known);
    std::vector<std::string> raw_functions;
    for (size_t i = 0; i + 1 < raw.size(); ++i) {
        if (raw[i].line_start && is_name_token(raw[i]) && raw[i + 1].kind == Tok::LParen && !raw[i + 1].space_before)
            for (size_t j = i + 2; j < raw.size() && raw[j].kind != Tok::Newline && raw[j].kind != Tok::End; ++j)
                if (raw[j].kind == Tok::RParen) {
                    if (raw[j + 1].kind == Tok::Eq) raw_functions.push_back(raw[i].text);
                    break;
                }
        if (is_kw(raw[i], "from"))  // the names before it, back to the line start or an earlier `from`
            for (size_t j = i; j-- > 0 && raw[j].kind != Tok::Newline && !is_kw(raw[j], "from");)
                if (is_name_token(raw[j])) raw_functions.push_back(raw[j].text);
    }
    for (const auto& n : opts.known_names) raw_functions.push_back(n);  // built-ins and implicit imports
    known.insert(opts.known_names.begin(), opts.known_names.end());
    auto outside = WordSplitter::shared(opts.known_names);
    std::vector<Token> toks = split_words(raw, known, {&own, outside.get()});
    std::vector<Token>().swap(raw);  // free the unsplit tokens before the AST is built
    Parser p(sm, std::move(toks), std::move(known), diags);
    // Functions: `NAME(params) =` at a line start, and imported names.
    for (size_t i = 0; i + 1 < raw_functions.size(); ++i) p.functions_.insert(raw_functions[i]);
    if (!raw_functions.empty()) p.functions_.insert(raw_functions.back());
    return p.parse(std::move(name), opts.allow_header);
}

}  // namespace iqc
