// Lexer and parser units: tokens of the Unicode notation, letter runs split by declarations,
// matrices whose items are separated by spaces, documents' code blocks.
#include <catch2/catch.hpp>

#include "TestUtil.h"
#include "syntax/Lexer.h"
#include "syntax/Parser.h"

using namespace iqc;
using namespace iqc::test;

static std::vector<Token> lex_text(SourceManager& sm, const std::string& text) {
    FileId f = sm.add("t", text);
    return lex(sm, f, {{0, uint32_t(text.size())}});
}

static std::string kinds(const std::vector<Token>& toks) {
    std::string s;
    for (const auto& t : toks) {
        if (!s.empty()) s += " ";
        s += token_description(t.kind);
        if (!t.text.empty()) s += "[" + t.text + "]";
    }
    return s;
}

TEST_CASE("lexer: Unicode operators, superscripts, subscripts, fractions, backticks", "[syntax]") {
    SourceManager sm;
    CHECK(kinds(lex_text(sm, "‖q‖ - t_2")) == "'‖' name[q] '‖' '-' name[t] '_' number[2] end of line end of input");
    CHECK(kinds(lex_text(sm, "x² A⁻¹ vᵀ x₁ ½")) ==
          "name[x] superscript[2] name[A] superscript[-1] name[v] superscript[T] name[x] subscript[1] fraction[1/2] end of line end of input");
    CHECK(kinds(lex_text(sm, "`P_L`∘`k_d` ≤ ≥ ≠ ∈ ℝ³")) ==
          "`name`[P_L] '∘' `name`[k_d] '≤' '≥' '≠' '∈' 'ℝ' superscript[3] end of line end of input");
    CHECK(kinds(lex_text(sm, "2e-3 2e 1.5 .5")) == "number[2e-3] number[2] name[e] number[1.5] number[.5] end of line end of input");
    CHECK(kinds(lex_text(sm, "a # a comment\nb")) == "name[a] end of line name[b] end of line end of input");
    // A letter with combining marks is one letter: N̂ (N + U+0302).
    auto t = lex_text(sm, "N̂x");
    REQUIRE(t.size() >= 1);
    CHECK(t[0].text == "N̂x");
}

TEST_CASE("lexer: spans and columns count code points", "[syntax]") {
    SourceManager sm;
    FileId f = sm.add("t", "D = ‖q‖ - s");
    auto toks = lex(sm, f, {{0, uint32_t(sm.text(f).size())}});
    const Token& s = toks[6];
    REQUIRE(s.text == "s");
    LineCol lc = sm.line_col(f, s.span.begin);
    CHECK(lc.line == 1);
    CHECK(lc.col == 11);
}

static ast::Module parse_text(const std::string& text, Diagnostics& d, SourceManager& sm) {
    FileId f = sm.add("t.iql", text);
    return parse_module(sm, f, {{0, uint32_t(text.size())}}, "t", {}, d);
}

TEST_CASE("parser: header, statements, declarations with bounds and descriptions", "[syntax]") {
    SourceManager sm;
    Diagnostics d(sm);
    ast::Module m = parse_text("shape\nD = ‖q‖ - t_2\nq = (‖(p_1, p_3)‖ - t_1, p_2)\nwhere\np ∈ ℝ³\n"
                               "t ∈ [0,2]x[0,2] default = (0.77, 0.6): radii (major, minor)\n", d, sm);
    INFO(d.render());
    REQUIRE(!d.has_errors());
    CHECK(m.kind == ast::ModuleKind::Shape);
    REQUIRE(m.stmts.size() == 2);
    CHECK(m.stmts[0].name == "D");
    CHECK(m.stmts[1].source_line == "q = (‖(p_1, p_3)‖ - t_1, p_2)");
    REQUIRE(m.decls.size() == 2);
    CHECK(m.decls[1].bounds.size() == 2);
    CHECK(m.decls[1].description == "radii (major, minor)");
}

TEST_CASE("parser: matrix rows on several lines, items separated by spaces", "[syntax]") {
    SourceManager sm;
    Diagnostics d(sm);
    ast::Module m = parse_text("sin, cos from trigonometry\nR = [cos(θ) -sin(θ)\n     sin(θ) cos(θ)]\nwhere\nθ ∈ ℝ\n", d, sm);
    INFO(d.render());
    REQUIRE(!d.has_errors());
    REQUIRE(m.stmts.size() == 2);
    const ast::Expr& mat = *m.stmts[1].value;
    REQUIRE(mat.kind == ast::ExprKind::Matrix);
    CHECK(mat.rows.size() == 2);
    CHECK(mat.rows[0].size() == 2);
    CHECK(mat.rows[0][1]->kind == ast::ExprKind::Negate);
}

TEST_CASE("parser: `||` opens two absolute values where a single bar closes first, else a norm", "[syntax]") {
    // Found by a new-user trial: Quilez's onion, ||‖p‖ - 0.6| - 0.1| - 0.03, read `||` as the ASCII norm and
    // failed ("expected '||' to close the norm, found '|'").
    auto eval = [](const std::string& name, const std::string& d, const std::string& at) {
        auto f = write_temp(name + ".iql", "shape\nD = " + d + "\nwhere\np ∈ ℝ³\n");
        RunResult r = run_iqc("eval " + f.string() + " --set 'p=" + at + "'");
        INFO(r.err);
        return r;
    };
    RunResult onion = eval("onion", "||‖p‖ - 0.6| - 0.1| - 0.03", "(0, 0, 0)");
    CHECK(onion.exit_code == 0);
    CHECK_THAT(onion.out, Catch::Contains("D = 0.47"));  // ||0 - 0.6| - 0.1| - 0.03
    CHECK_THAT(eval("onion_shell", "||‖p‖ - 0.6| - 0.1| - 0.03", "(0.6, 0, 0)").out, Catch::Contains("D = 0.07"));
    // Two closed at once too: ||x| + |y|| is |(|x| + |y|)|.
    CHECK_THAT(eval("bars_sum", "||p_1| + |p_2|| - 1", "(-3, 4, 0)").out, Catch::Contains("D = 6"));
    // The ASCII norm stays a norm, also around absolute values inside ‖…‖ or brackets.
    CHECK_THAT(eval("ascii_norm", "||p|| - 1", "(3, 4, 0)").out, Catch::Contains("D = 4"));
    CHECK_THAT(eval("ascii_norm_abs", "||(|p_1|, p_2, p_3)|| - 1", "(-3, 4, 0)").out, Catch::Contains("D = 4"));
    // Unclosed: the message says which bar is missing, and where it opened.
    RunResult bad = eval("bars_open", "||p_1| - 5", "(0, 0, 0)");
    CHECK(bad.exit_code == 1);
    CHECK_THAT(bad.err, Catch::Contains("error: expected '|' to close the absolute value"));
    CHECK_THAT(bad.err, Catch::Contains("bars_open.iql:2:5: note: opened here"));
}
