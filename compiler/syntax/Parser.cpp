#include "syntax/Parser.h"

#include <cctype>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fmt/format.h>
#include <limits>

#include "source/Limits.h"
#include "syntax/WordSplit.h"

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
                                         "default", "shape", "material", "scalar", "vector", "matrix", "for"};

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
                    (is_name_token(toks[k + 2]) || toks[k + 2].kind == Tok::Number) && !toks[k + 2].space_before &&
                    !sequences.count(n)) {
                    names.push_back(n);
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
    bool failed_ = false;  // an error in the current statement: skip to its end
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
        if (!(std::fabs(v) <= double(std::numeric_limits<float>::max())))
            fail(t.span, fmt::format("the number {} is outside the range of 32-bit floats (at most about 3.4e38), "
                                     "which shaders compute in", t.text));
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
            case Tok::Unknown: return fmt::format("'{}'", t.text);
            default: return token_description(t.kind);
        }
    }
    Span prev_span() const { return toks_[pos_ > 0 ? pos_ - 1 : 0].span; }
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
    Decl parse_decl();
    TypeSpec parse_type();
    std::vector<std::pair<std::string, Span>> parse_name_list();
    std::pair<std::string, Span> parse_name();

    ExprPtr parse_condition();
    ExprPtr parse_comparison();
    ExprPtr parse_expr();
    ExprPtr parse_unary();
    ExprPtr parse_mult();
    ExprPtr parse_operand();  // operand of an explicit operator: allows a leading sign
    ExprPtr parse_elem();
    ExprPtr parse_power();
    ExprPtr parse_postfix(bool exponent = false);
    ExprPtr parse_primary();
    ExprPtr parse_matrix(Span open);
    ExprPtr parse_piecewise(Span open);
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
        if ((is_name_token(sub) || sub.kind == Tok::Number) && !sub.space_before && known_.count(n + "_" + sub.text)) {
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
        if (toks_[k].kind == Tok::Underscore && k + 1 < toks_.size() && is_name_token(toks_[k + 1]) &&
            known_.count(toks_[k - 1].text + "_" + toks_[k + 1].text))
            k += 2;
        else if (toks_[k].kind == Tok::Underscore && k + 1 < toks_.size() && toks_[k + 1].kind == Tok::Number &&
                 known_.count(toks_[k - 1].text + "_" + toks_[k + 1].text))
            k += 2;
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

// type := ℝ [SUPER | ^ dims] | ℤ | R [^ dims] | Z | scalar | vector(n) | matrix(m, n) | type {, type} → type
TypeSpec Parser::parse_type() {
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
            parse_dim(ts.rows, ts.sym_rows);
            if (accept(Tok::Cross) || (at(Tok::Word) && cur().text == "x" && (advance(), true)) || accept(Tok::Comma)) {
                parse_dim(ts.cols, ts.sym_cols);
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
    if (at(Tok::Comma) || at(Tok::Arrow)) {
        size_t save = pos_;
        std::vector<TypeSpec> params;
        params.push_back(std::move(ts));
        bool ok = true;
        while (accept(Tok::Comma)) {
            if (!(at(Tok::Reals) || at(Tok::Integers) || at_kw("scalar") || at_kw("vector") || at_kw("matrix") ||
                  (at(Tok::Word) && (cur().text == "R" || cur().text == "Z")))) { ok = false; break; }
            params.push_back(parse_type());
        }
        if (ok && accept(Tok::Arrow)) {
            TypeSpec f;
            f.kind = TypeSpec::Function;
            f.params = std::move(params);
            f.result = std::make_unique<TypeSpec>(parse_type());
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
    d.names = parse_name_list();
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
    }
    if (at_kw("default")) {
        Span ds = advance().span;
        expect(Tok::Eq, "after 'default'");
        d.default_value = parse_expr();
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
        s.params = parse_name_list();
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
    if (toks_[k].kind == Tok::Number || is_name_token(toks_[k])) return toks_[k + 1].kind == Tok::Eq;
    if (toks_[k].kind != Tok::LParen) return false;
    int depth = 0;
    for (; toks_[k].kind != Tok::Newline && toks_[k].kind != Tok::End; ++k) {
        if (toks_[k].kind == Tok::LParen) ++depth;
        if (toks_[k].kind == Tok::RParen && --depth == 0) return toks_[k + 1].kind == Tok::Eq;
    }
    return false;
}

// sequence := NAME _ INDEX = expr                         (its first element, e.g. z_1 = p)
//           | NAME _ ( VAR + 1 ) = expr for VAR (∈ | = | in) lo .. hi   (the recurrence)
Stmt Parser::parse_indexed_assignment(std::pair<std::string, Span> name, Span start) {
    Stmt s;
    s.name = name.first;
    s.name_span = name.second;
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
    while (!at(Tok::End)) {
        if (at(Tok::Newline) || at(Tok::Semicolon)) { advance(); continue; }
        try {
            ctx_.assign(1, Ctx::Top);
            Span start = cur().span;
            parse_line(m);
            if (!at(Tok::Newline) && !at(Tok::End) && !at(Tok::Semicolon)) {
                const Token& t = cur();
                if (t.kind == Tok::Unknown)
                    fail(t.span, fmt::format("unexpected character '{}'", t.text));
                if (t.kind == Tok::Eq) suggest_backticks(start, t.span);
                fail(t.span, fmt::format("unexpected {} after the end of the statement", describe(t)));
            }
        } catch (Bail&) {
            skip_line();
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
        if (t.kind != Tok::Plus && t.kind != Tok::Minus) break;
        // Inside a matrix, `a -b` is two items while `a - b` and `a-b` are one.
        if (ctx_.back() == Ctx::Bracket && t.space_before && !peek_raw(1).space_before) break;
        nest(depth, t.span);
        BinOp op = t.kind == Tok::Plus ? BinOp::Add : BinOp::Sub;
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
        case Tok::Word: return !is_keyword(t.text);
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

// elem := power {(∘ | ×) power}
ExprPtr Parser::parse_elem() {
    limits::DepthGuard depth(depth_);
    ExprPtr lhs = parse_power();
    while (at(Tok::Circle) || at(Tok::Cross)) {
        nest(depth, cur().span);
        BinOp op = at(Tok::Circle) ? BinOp::Hadamard : BinOp::Cross;
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
            if (t.text.empty() || t.text.find_first_not_of("+-0123456789") != std::string::npos ||
                t.text.find_first_of("0123456789") == std::string::npos)
                fail(t.span, "a superscript power must be an integer such as ² or ⁻¹");
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
            nest(depth, cur().span);
            advance();
            auto idx = make(ExprKind::Index, e->span);
            idx->args.push_back(std::move(e));
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
                    advance();
                    ctx_.push_back(Ctx::Paren);
                    it.expr = parse_expr();
                    ctx_.pop_back();
                    it.span = Span::join(t.span, expect(Tok::RParen, "to close the subscript").span);
                } else {
                    fail(t.span, fmt::format("expected a subscript after '_', found {}", describe(t)));
                }
                idx->span = Span::join(idx->span, it.span);
                idx->indices.push_back(std::move(it));
            };
            parse_index();
            // A second index (`A_2,3`) only outside parenthesised lists, written without spaces.
            if (ctx_.back() == Ctx::Top && toks_[pos_].kind == Tok::Comma && !toks_[pos_].space_before &&
                !peek_raw(1).space_before)
                advance(), parse_index();
            e = std::move(idx);
            continue;
        }
        bool callable = !exponent || functions_.count(e->text) || letter_units(e->text).size() > 1;
        if (at(Tok::LParen) && !cur().space_before && e->kind == ExprKind::Name && callable) {
            nest(depth, cur().span);
            Span open = advance().span;
            ctx_.push_back(Ctx::Paren);
            auto call = make(ExprKind::Call, e->span);
            call->text = e->text;
            call->name_span = e->name_span;
            if (!at(Tok::RParen)) {
                call->args.push_back(parse_expr());
                while (accept(Tok::Comma)) call->args.push_back(parse_expr());
            }
            ctx_.pop_back();
            Span close = expect(Tok::RParen, "to close the argument list").span;
            (void)open;
            call->span = Span::join(call->span, close);
            e = std::move(call);
            continue;
        }
        break;
    }
    return e;
}

ExprPtr Parser::parse_delimited(ExprKind kind, Tok close, Span open, const char* what) {
    ctx_.push_back(kind == ExprKind::Norm || kind == ExprKind::Abs ? Ctx::Bars : Ctx::Paren);
    ExprPtr inner = parse_expr();
    ctx_.pop_back();
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

// piecewise := { case {newline case}      case := expr [,] (if condition | otherwise)
ExprPtr Parser::parse_piecewise(Span open) {
    ctx_.push_back(Ctx::Brace);
    auto p = make(ExprKind::Piecewise, open);
    while (true) {
        while (at(Tok::Newline)) advance();
        if (at(Tok::RBrace)) { advance(); break; }
        ExprPtr value = parse_expr();
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
            e->number = literal_value(t);
            e->text = t.text;
            advance();
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
            if (t.kind == Tok::Word && is_keyword(t.text))
                fail(t.span, fmt::format("unexpected keyword '{}' in an expression", t.text));
            auto e = make(ExprKind::Name, t.span);
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
        case Tok::Norm: return parse_delimited(ExprKind::Norm, Tok::Norm, advance().span, "the norm");
        case Tok::DoubleBar: return parse_delimited(ExprKind::Norm, Tok::DoubleBar, advance().span, "the norm");
        case Tok::Bar: return parse_delimited(ExprKind::Abs, Tok::Bar, advance().span, "the absolute value");
        case Tok::LFloor: return parse_delimited(ExprKind::Floor, Tok::RFloor, advance().span, "the floor");
        case Tok::LCeil: return parse_delimited(ExprKind::Ceil, Tok::RCeil, advance().span, "the ceiling");
        case Tok::Sum: {
            // ∑_i term: the summand is a multiplicative term, so ∑_i a_i b_i + c is (∑_i a_i b_i) + c.
            Span s = advance().span;
            std::string index;
            if (at(Tok::Sub)) {
                index = advance().text;
            } else if (at(Tok::Underscore)) {
                advance();
                if (!is_name_token(cur())) fail(cur().span, fmt::format("expected the summation index after '∑_', found {}", describe(cur())));
                index = advance().text;
            } else {
                fail(cur().span, "expected a summation index, as in ∑_i v_i");
            }
            ExprPtr body = parse_mult();
            auto e = make(ExprKind::Sum, Span::join(s, body->span));
            e->text = index;
            e->args.push_back(std::move(body));
            return e;
        }
        case Tok::Sqrt: {
            Span s = advance().span;
            ExprPtr inner = parse_postfix();
            auto e = make(ExprKind::Sqrt, Span::join(s, inner->span));
            e->args.push_back(std::move(inner));
            return e;
        }
        case Tok::Unknown: fail(t.span, fmt::format("unexpected character '{}'", t.text));
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
