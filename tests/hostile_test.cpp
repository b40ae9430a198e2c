// Hostile input: every reproducer of issue 16 (crashes, hangs, comment injection, wrong exit codes) runs
// the real binary under a time and memory bound and must end with exit 0 or with exit 1 and a located
// diagnostic (file:line:col, the line and a caret). Small inputs are files in tests/hostile/; large ones
// are generated here. The limits they meet are in compiler/source/Limits.h.
#include <catch2/catch.hpp>

#include <sys/stat.h>

#include <chrono>
#include <regex>

#include <fmt/format.h>

#include "TestUtil.h"
#include "glsl/Names.h"
#include "source/Limits.h"
#include "source/Sanitizer.h"

using namespace iqc;
using namespace iqc::test;
namespace fs = std::filesystem;

namespace {

std::string hostile(const std::string& name) { return std::string(IQC_SOURCE_DIR) + "/tests/hostile/" + name; }

struct Bounded {
    RunResult run;
    double seconds = 0;
};

// Runs iqc with 10 s of wall time and 2 GB of address space (the bounds). Sanitizer builds reserve
// terabytes of address space for their shadow memory and run several times slower, so there only a time
// bound applies, of 120 s.
Bounded run_bounded(const std::string& args) {
    std::string limit = kAddressSanitizerBuild ? "timeout 120" : "ulimit -v 2097152; timeout 10";
    auto t0 = std::chrono::steady_clock::now();
    Bounded b;
    b.run = run_iqc_env(limit, args);
    b.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return b;
}

// Exit 1 with `location: error: message` (message: a prefix; a location ending in ':' matches any
// line and column after it), followed by the source line and a caret line.
void require_located(const Bounded& b, const std::string& location, const std::string& message) {
    INFO("stderr: " << b.run.err.substr(0, 2000));
    CHECK(b.run.exit_code == 1);
    size_t at = std::string::npos;
    for (size_t from = 0; (from = b.run.err.find(location, from)) != std::string::npos; ++from) {
        size_t k = from + location.size();
        if (location.back() == ':')
            while (k < b.run.err.size() && (std::isdigit(static_cast<unsigned char>(b.run.err[k])) || b.run.err[k] == ':') &&
                   b.run.err.compare(k, 2, ": ") != 0)
                ++k;
        if (b.run.err.compare(k, 9 + message.size(), ": error: " + message) == 0) {
            at = from;
            break;
        }
    }
    REQUIRE(at != std::string::npos);
    size_t eol = b.run.err.find('\n', at);
    REQUIRE(eol != std::string::npos);
    size_t eol2 = b.run.err.find('\n', eol + 1);
    REQUIRE(eol2 != std::string::npos);
    std::string caret_line = b.run.err.substr(eol2 + 1, b.run.err.find('\n', eol2 + 1) - eol2 - 1);
    CHECK(std::regex_match(caret_line, std::regex("  *\\^~*")));
}

fs::path generated(const std::string& name, const std::string& text) {
    fs::create_directories(temp_dir() / "hostile");
    return write_temp("hostile/" + name, text);
}

std::string repeat(const std::string& s, size_t n) {
    std::string out;
    out.reserve(s.size() * n);
    for (size_t i = 0; i < n; ++i) out += s;
    return out;
}

}  // namespace

TEST_CASE("a value called with no arguments is a located error, not a crash", "[hostile]") {
    require_located(run_bounded("eval " + hostile("value_call.iql")), hostile("value_call.iql") + ":1:5",
                    "'x' is a value, not a function: 'x()' has nothing to multiply it by");
    require_located(run_bounded(hostile("value_call_shape.iql") + " -o -"), hostile("value_call_shape.iql") + ":2:11",
                    "'r' is a value, not a function");
    require_located(run_bounded(hostile("pi_call.iql") + " -o -"), hostile("pi_call.iql") + ":2:11",
                    "'π' is a value, not a function");
}

TEST_CASE("an empty backtick name is a located error, not a size of 0", "[hostile]") {
    // Found by stop 27's ir fuzzing: `ℝ^``` read as ℝ⁰ and the evaluator aborted (exit 3).
    std::string size = (fs::path(IQC_SOURCE_DIR) / "tests" / "fuzz" / "ir" / "empty_backtick_size.iql").string();
    require_located(run_bounded("eval " + size), size + ":1:7", "expected a size, found an empty name ``");
    require_located(run_bounded("eval " + hostile("empty_backtick.iql")), hostile("empty_backtick.iql") + ":1:5",
                    "a name between backticks cannot be empty");
}

TEST_CASE("invalid UTF-8 in a description reaches --meta as U+FFFD, not an abort", "[hostile]") {
    fs::path meta = temp_dir() / "bad_utf8.json";
    Bounded b = run_bounded(hostile("bad_utf8_description.iql") + " -o - --meta " + meta.string());
    INFO(b.run.err);
    REQUIRE(b.run.exit_code == 0);
    CHECK_THAT(read_text(meta), Catch::Contains("\"description\": \"radius \xEF\xBF\xBD\xEF\xBF\xBD bytes\""));
    CHECK_THAT(b.run.out, Catch::Contains("// r ∈ [0, 2]: radius \xEF\xBF\xBD\xEF\xBF\xBD bytes"));
}

TEST_CASE("sizes are checked once: too large, wrapping, beyond int, products", "[hostile]") {
    std::string cap = std::to_string(limits::kMaxComponents);
    require_located(run_bounded("eval " + hostile("size_overflow.iql")), hostile("size_overflow.iql") + ":3:8",
                    "the size 65536 is too large: iqc allows at most " + cap + " components per vector or matrix");
    require_located(run_bounded("eval " + hostile("size_wrap.iql")), hostile("size_wrap.iql") + ":3:8",
                    "the size 65536 is too large");
    require_located(run_bounded("eval " + hostile("size_atoi.iql")), hostile("size_atoi.iql") + ":3:8",
                    "the size 4294967299 is too large");
    require_located(run_bounded("eval " + hostile("size_product.iql")), hostile("size_product.iql") + ":3:5",
                    "'A' would have 100×100 components: iqc allows at most " + cap);
    require_located(run_bounded("eval " + hostile("sum_huge.iql")), hostile("sum_huge.iql") + ":3:8",
                    "the size 100000000 is too large");
    // Sizes computed by the checker: a concatenation and an outer product past the cap.
    fs::path concat = generated("concat.iql", "y = (v, v, v)\nwhere\nv ∈ ℝ^2000\n");
    require_located(run_bounded("eval " + concat.string()), concat.string() + ":1:5", "this vector has 6000 components");
    fs::path outer = generated("outer.iql", "y = v vᵀ\nwhere\nv ∈ ℝ^100\n");
    require_located(run_bounded("eval " + outer.string()), outer.string() + ":1:5", "this value has 10000 components");
    fs::path subscript = generated("subscript.iql", "y = v_99999999999\nwhere\nv ∈ ℝ³\n");
    require_located(run_bounded("eval " + subscript.string()), subscript.string() + ":1:7",
                    "subscript 99999999999 is out of range");
}

TEST_CASE("deep nesting is a located error: long chains of statements are fine", "[hostile]") {
    std::string cap = std::to_string(limits::kMaxNesting);
    fs::path parens = generated("parens.iql", "y = " + repeat("(", 7000) + "1" + repeat(")", 7000) + "\n");
    Bounded p = run_bounded("eval " + parens.string());
    require_located(p, parens.string() + ":1:", "the expression nests deeper than " + cap + " levels");
    std::string terms = "1";
    for (int i = 1; i < 20000; ++i) terms += " + 1";
    fs::path sum = generated("sum.iql", "y = " + terms + "\n");
    require_located(run_bounded("eval " + sum.string()), sum.string() + ":1:", "the expression nests deeper than");
    // Just under the limit everything works, through every pass to GLSL: a sum of 240 terms, 60 nested
    // parentheses (three levels each).
    std::string ok_terms = "1";
    for (int i = 1; i < 240; ++i) ok_terms += " + 1";
    Bounded ok = run_bounded("eval " + generated("sum240.iql", "y = " + ok_terms + "\n").string());
    CHECK(ok.run.exit_code == 0);
    CHECK(ok.run.out == "y = 240\n");
    std::string shape_terms = "‖p‖";
    for (int i = 1; i < 240; ++i) shape_terms += " + p_" + std::to_string(1 + i % 3) + "/" + std::to_string(i + 1000);
    fs::path deep_shape = generated("deep_shape.iql", "shape\nD = " + shape_terms + " - q\nq = " + repeat("(", 60) + "p_1" +
                                                          repeat(")", 60) + "\nwhere\np ∈ ℝ³\n");
    for (const char* target : {"shadertoy", "webgl2"}) {
        Bounded g = run_bounded(deep_shape.string() + " --target " + target + " -o /dev/null");
        INFO(g.run.err.substr(0, 2000));
        CHECK(g.run.exit_code == 0);
    }
    // 50,000 statements, each using the one after it: ordered without recursion.
    std::string chain = "y = `a_50000`\n";
    for (int i = 50000; i > 1; --i) chain += "`a_" + std::to_string(i) + "` = `a_" + std::to_string(i - 1) + "` + 1\n";
    chain += "`a_1` = 1\n";
    Bounded c = run_bounded("eval " + generated("chain.iql", chain).string());
    INFO(c.run.err);
    CHECK(c.run.exit_code == 0);
    CHECK_THAT(c.run.out, Catch::StartsWith("y = 50000\n"));
    // A dependency cycle through 2,000 statements is reported with its ends, not 2,000 names.
    std::string cycle;
    for (int i = 1; i <= 2000; ++i) cycle += "`c_" + std::to_string(i) + "` = `c_" + std::to_string(i % 2000 + 1) + "` + 1\n";
    fs::path cyc = generated("cycle.iql", cycle);
    Bounded cy = run_bounded("eval " + cyc.string());
    require_located(cy, cyc.string() + ":1:1", "dependency cycle: c_1 → c_2 → ");
    CHECK_THAT(cy.run.err, Catch::Contains("… (1988 more) → c_2000 → c_1"));
    // Local functions calling local functions: the checker's own depth limit.
    std::string fns = "y = `f_1`(1)\n";
    for (int i = 1; i < 3000; ++i) fns += "`f_" + std::to_string(i) + "`(x) = `f_" + std::to_string(i + 1) + "`(x) + 1 where x ∈ ℝ\n";
    fns += "`f_3000`(x) = x where x ∈ ℝ\n";
    // 80 local functions calling each other: fine, evaluated and compiled to GLSL.
    std::string few = "shape\nD = ‖p‖ - `f_1`(p_1)\n";
    for (int i = 1; i < 80; ++i) few += "`f_" + std::to_string(i) + "`(x) = `f_" + std::to_string(i + 1) + "`(x) + 1 where x ∈ ℝ\n";
    few += "`f_80`(x) = x where x ∈ ℝ\nwhere\np ∈ ℝ³\n";
    fs::path few_path = generated("functions80.iql", few);
    Bounded fc = run_bounded(few_path.string() + " -o /dev/null");
    INFO(fc.run.err.substr(0, 2000));
    CHECK(fc.run.exit_code == 0);
    fs::path fn = generated("functions.iql", fns);
    require_located(run_bounded("eval " + fn.string()), fn.string() + ":",
                    "expressions and the local functions they call nest deeper than " + cap + " levels");
}

TEST_CASE("a 100,000-part dotted TOML key is a located error", "[hostile]") {
    fs::path dotted = generated("dotted.iq", "a" + repeat(".a", 100000) + " = 1\n[[shapes]]\ntype = \"sphere\"\n");
    require_located(run_bounded(dotted.string() + " -o -"), dotted.string() + ":1:258",
                    "the TOML nests deeper than " + std::to_string(limits::kMaxTomlDepth) + " levels here");
}

TEST_CASE("imports nest at most 64 deep", "[hostile]") {
    fs::path dir = temp_dir() / "hostile" / "imports";
    fs::create_directories(dir);
    for (int i = 1; i <= 100; ++i) {
        std::string body = i < 100 ? "`g_" + std::to_string(i) + "` from `m_" + std::to_string(i + 1) + "`\n" : "";
        body += "`g_" + std::to_string(i - 1) + "`(x) = " + (i < 100 ? "`g_" + std::to_string(i) + "`(x)" : "x") + " where x ∈ ℝ\n";
        std::ofstream(dir / ("m_" + std::to_string(i) + ".iql")) << body;
    }
    std::ofstream(dir / "main.iql") << "`g_0` from `m_1`\ny = `g_0`(2)\n";
    Bounded b = run_bounded("eval " + (dir / "main.iql").string());
    INFO(b.run.err);
    CHECK(b.run.exit_code == 1);
    CHECK_THAT(b.run.err, Catch::Contains("is imported through more than " + std::to_string(limits::kMaxImportDepth) +
                                          " nested imports"));
}

TEST_CASE("name splitting and scene reading are linear", "[hostile]") {
    // The cubic case: a 12,800-letter run with known names that almost match everywhere. It splits into
    // 6,400 products, past the nesting limit: a located error, quickly.
    std::string run = repeat("ab", 6400);
    fs::path letters = generated("letters.iql", "y = " + run + "\nwhere\na ∈ ℝ\nb ∈ ℝ\n`abab` ∈ ℝ\n`ababa` ∈ ℝ\n");
    Bounded l = run_bounded("eval " + letters.string());
    require_located(l, letters.string() + ":1:", "the expression nests deeper than");
    CHECK(l.seconds < 10);
    // A declared 12,800-letter name is one name.
    fs::path longname = generated("longname.iql", "y = " + run + " + 1\nwhere\n`" + run + "` ∈ ℝ default = 2\n");
    Bounded n = run_bounded("eval " + longname.string());
    INFO(n.run.err);
    CHECK(n.run.exit_code == 0);
    CHECK(n.run.out == "y = 3\n");
    // 10,000 named shapes, each with a transform: read and compiled within the bound (reading rescanned the
    // file per TOML node, and planning copied the set of names per instance).
    std::string scene;
    for (int i = 0; i < 10000; ++i)
        scene += "[[shapes]]\nname = \"s" + std::to_string(i) + "\"\ntype = \"sphere\"\ntransform = \"T((" +
                 std::to_string(i % 100) + ", " + std::to_string(i / 100) + ", 0))\"\n";
    Bounded s = run_bounded(generated("shapes10000.iq", scene).string() + " -o /dev/null");
    INFO(s.run.err);
    CHECK(s.run.exit_code == 0);
}

TEST_CASE("iqc eval refuses a recurrence too long to evaluate", "[hostile]") {
    require_located(run_bounded("eval " + hostile("recurrence_huge.iql")), hostile("recurrence_huge.iql") + ":2:1",
                    "evaluating this would take more than " + std::to_string(limits::kMaxEvalSteps) + " steps");
    // A range end past what GLSL's int loops count is refused by the checker.
    fs::path far = generated("far.iql", "z_1 = 0\nz_(k+1) = z_k + 1 for k ∈ 1..1e12\ny = z_1\n");
    require_located(run_bounded("eval " + far.string()), far.string() + ":2:30",
                    "the end of a recurrence's range must be within ±1000000000");
}

TEST_CASE("files are read only when regular and not too large", "[hostile]") {
    require_located(run_bounded(hostile("include_dev_zero.iq") + " -o -"), hostile("include_dev_zero.iq") + ":1:12",
                    "cannot read included file '/dev/zero': it is not a regular file");
    // A named pipe nobody writes to: refused at once, never waited on.
    fs::path dir = temp_dir() / "hostile" / "fifo";
    fs::create_directories(dir);
    fs::remove(dir / "pipe.iql");
    REQUIRE(mkfifo((dir / "pipe.iql").c_str(), 0600) == 0);
    std::ofstream(dir / "scene.iq") << "include = [\"pipe.iql\"]\n[[shapes]]\ntype = \"sphere\"\n";
    Bounded p = run_bounded((dir / "scene.iq").string() + " -o -");
    require_located(p, (dir / "scene.iq").string() + ":1:12", "cannot read included file");
    CHECK_THAT(p.run.err, Catch::Contains("not a regular file"));
    Bounded direct = run_bounded("eval " + (dir / "pipe.iql").string());
    CHECK(direct.run.exit_code == 1);
    CHECK_THAT(direct.run.err, Catch::Contains("not a regular file"));
    // A module file beside the scene that is a pipe is not a module file.
    std::ofstream(dir / "named.iq") << "[[shapes]]\ntype = \"pipe\"\n";
    require_located(run_bounded((dir / "named.iq").string() + " -o -"), (dir / "named.iq").string() + ":2:8",
                    "unknown shape 'pipe'");
    // Larger than the limit on one file.
    std::string big(limits::kMaxFileBytes + 1, '#');
    fs::path large = generated("large.iql", big);
    std::ofstream(temp_dir() / "hostile" / "large_scene.iq") << "include = [\"large.iql\"]\n[[shapes]]\ntype = \"sphere\"\n";
    Bounded l = run_bounded((temp_dir() / "hostile" / "large_scene.iq").string() + " -o -");
    require_located(l, (temp_dir() / "hostile" / "large_scene.iq").string() + ":1:12", "cannot read included file");
    CHECK_THAT(l.run.err, Catch::Contains("it is larger than 16 MiB"));
    fs::remove(large);
}

TEST_CASE("user text in comments cannot inject code", "[hostile]") {
    for (const char* target : {"shadertoy", "webgl2", "glsl330", "wgsl"}) {
        Bounded b = run_bounded(hostile("injection.iq") + " --target " + target + " -o -");
        INFO(target << "\n" << b.run.err);
        REQUIRE(b.run.exit_code == 0);
        std::istringstream lines(b.run.out);
        std::string line;
        int comments_with_names = 0;
        while (std::getline(lines, line)) {
            size_t slash = line.find("//");
            std::string code = line.substr(0, slash);
            INFO(line);
            CHECK(code.find("int injected") == std::string::npos);
            CHECK(code.find("#define IQC_BACKGROUND vec3(1.0, 0.0, 0.0)") == std::string::npos);
            CHECK(code.find("IQC_FOG 9.0") == std::string::npos);
            CHECK(line.find("/*") == std::string::npos);
            CHECK(line.find("*/") == std::string::npos);
            CHECK((line.empty() || line.back() != '\\'));
            if (slash != std::string::npos && line.find("injected", slash) != std::string::npos) ++comments_with_names;
        }
        // the names are still there, as comments (wgsl keeps only the title: its code comes from SPIR-V)
        if (std::string(target) != "wgsl") CHECK(comments_with_names >= 4);
        else CHECK_THAT(b.run.out, Catch::StartsWith("// title #define IQC_BACKGROUND"));
    }
    // A module name with a newline is no name at all (it could not be a .iql file's): a located error.
    fs::path nl = generated("newline_module.iq", "[modules]\n\"evil\\nint injected_module;\" = \"\"\"\nshape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n\"\"\"\n");
    require_located(run_bounded(nl.string() + " -o -"), nl.string() + ":2:1", "'evil\\nint injected_module;' cannot name a module");
}

TEST_CASE("a hand-written shader that crashes the driver's or glslang's compiler is a diagnostic, not iqc's crash", "[hostile][render]") {
    // Found by a re-trial of issue 16: a sum of 20,000 terms overflowed the stack of Mesa's GLSL compiler (render)
    // and a chain of 10,000 commas glslang's SPIR-V generator (wgsl): iqc died with them (exit 139). Each is
    // tried in a child process first.
    std::string sum = "void mainImage(out vec4 c, in vec2 f) {\n    float x = 0.0\n";
    for (int i = 0; i < 20000; ++i) sum += "        + 1.0\n";
    sum += "    ;\n    c = vec4(x);\n}\n";
    fs::path big = generated("long_sum.frag", sum);
    Bounded r = run_bounded("render " + big.string() + " --size 16x9 -o " + (temp_dir() / "long_sum.png").string());
    INFO(r.run.err);
    CHECK(r.run.exit_code == 1);
    CHECK_THAT(r.run.err, Catch::Contains("long_sum.frag: the GL driver crashed compiling this shader ("));
    std::string commas = "void mainImage(out vec4 c, in vec2 f) {\n    float x = (1.0";
    for (int i = 0; i < 10000; ++i) commas += ",1.0";
    commas += ");\n    c = vec4(x);\n}\n";
    fs::path comma = generated("long_comma.frag", commas);
    Bounded w = run_bounded(comma.string() + " --target wgsl -o " + (temp_dir() / "long_comma.wgsl").string());
    INFO(w.run.err);
    CHECK(w.run.exit_code == 1);
    CHECK_THAT(w.run.err, Catch::Contains("long_comma.frag: glslang crashed compiling this shader ("));
    CHECK_FALSE(fs::exists(temp_dir() / "long_comma.wgsl"));
}

TEST_CASE("comment_text: one line, no comment delimiters, no continuation, valid UTF-8", "[hostile]") {
    CHECK(glsl::comment_text("a\nb\r\nc\vd\fe") == "a b c d e");
    CHECK(glsl::comment_text("x\xC2\x85y\xE2\x80\xA8z\xE2\x80\xA9w") == "x y z w");  // NEL, U+2028, U+2029
    CHECK(glsl::comment_text(std::string("n\0ul", 4)) == "n ul");
    CHECK(glsl::comment_text("a */ b /* c") == "a * / b / * c");
    CHECK(glsl::comment_text("ends \\") == "ends");
    CHECK(glsl::comment_text("ends \\ \\\\  ") == "ends");
    // (C0 can start no well-formed sequence: each of its bytes is replaced, as Unicode's "maximal subpart" rule says)
    CHECK(glsl::comment_text("bad \xFF byte, overlong \xC0\xAF slash") == "bad \xEF\xBF\xBD byte, overlong \xEF\xBF\xBD\xEF\xBF\xBD slash");
    CHECK(glsl::comment_text("‖p‖ - r: keeps math") == "‖p‖ - r: keeps math");
    // Invisible format characters are spelled out (Trojan Source): bidi override and isolate, zero-width, BOM.
    CHECK(glsl::comment_text("a\u202Eb\u2066c\u200Dd\uFEFFe") == "a<U+202E>b<U+2066>c<U+200D>d<U+FEFF>e");
}

TEST_CASE("invisible characters in source are errors, spelled in the message and never echoed raw", "[hostile]") {
    // Found by a new-user trial: a stray combining mark and a zero-width space read as whitespace, so `3 ́ 4` was
    // 3·4 = 12 and `a​b` was a·b, silently; a right-to-left override was echoed raw and flipped the terminal's line.
    fs::path mark = generated("stray_mark.iql", "y = 3 \u0301 4\n");
    require_located(run_bounded("eval " + mark.string()), mark.string() + ":1:7", "unexpected character '<U+0301>'");
    fs::path zw = generated("zero_width.iql", "y = a\u200Bb\nwhere\na ∈ ℝ default = 2\nb ∈ ℝ default = 5\n");
    require_located(run_bounded("eval " + zw.string()), zw.string() + ":1:6", "unexpected character '<U+200B>'");
    fs::path bidi = generated("bidi.iql", "y = 1 - \u202Er\nwhere\nr ∈ ℝ default = 2\n");
    Bounded b = run_bounded("eval " + bidi.string());
    require_located(b, bidi.string() + ":1:9", "unexpected character '<U+202E>'");
    CHECK(b.run.err.find("\u202E") == std::string::npos);  // not echoed: U+FFFD stands in the source line
    CHECK_THAT(b.run.err, Catch::Contains("  y = 1 - \uFFFDr\n          ^"));
    fs::path nbsp = generated("nbsp.iql", "y = 1\u00A0+ 2\n");
    Bounded nb = run_bounded("eval " + nbsp.string());
    require_located(nb, nbsp.string() + ":1:6", "unexpected character '<U+00A0>'");
    CHECK_THAT(nb.run.err, Catch::Contains("  y = 1\uFFFD+ 2\n       ^"));  // shown, not a space that looks like one
    fs::path bad = generated("bad_byte.iql", "y = 1 \xFF 2\n");
    require_located(run_bounded("eval " + bad.string()), bad.string() + ":1:7", "unexpected character '<byte 0xFF>'");
    // Not UTF-8: an overlong '/' (C0 AF was read as a division) and a surrogate are bytes of their own; a BOM
    // within a line is a zero-width no-break space; an invisible filler is named.
    fs::path overlong = generated("overlong.iql", "y = 6 \xC0\xAF 2\n");
    require_located(run_bounded("eval " + overlong.string()), overlong.string() + ":1:7", "unexpected character '<byte 0xC0>'");
    fs::path surrogate = generated("surrogate.iql", "y = 1 \xED\xA0\x80 2\n");
    require_located(run_bounded("eval " + surrogate.string()), surrogate.string() + ":1:7", "unexpected character '<byte 0xED>'");
    fs::path midbom = generated("mid_bom.iql", "y = 1 \uFEFF+ 2\n");
    require_located(run_bounded("eval " + midbom.string()), midbom.string() + ":1:7", "unexpected character '<U+FEFF>'");
    fs::path filler = generated("filler.iql", "y = 1 \u115F 2\n");
    require_located(run_bounded("eval " + filler.string()), filler.string() + ":1:7", "unexpected character '<U+115F>'");
    // A combining mark after a letter is part of the name (x̂), and a BOM is whitespace.
    fs::path hat = generated("hat.iql", "\uFEFFy = x\u0302 + 1\nwhere\nx\u0302 ∈ ℝ default = 2\n");
    Bounded h = run_bounded("eval " + hat.string());
    INFO(h.run.err);
    CHECK(h.run.exit_code == 0);
    CHECK(h.run.out == "y = 3\n");
}

TEST_CASE("literals outside float's range are located errors: folded overflow is not an internal error", "[hostile]") {
    require_located(run_bounded(hostile("float_range.iql") + " -o -"), hostile("float_range.iql") + ":2:11",
                    "the number 1e39 is outside the range of 32-bit floats");
    Bounded folded = run_bounded(hostile("float_folded.iql") + " -o -");
    INFO(folded.run.err);
    CHECK(folded.run.exit_code == 0);
    require_located(run_bounded(hostile("toml_inf.iq") + " -o -"), hostile("toml_inf.iq") + ":2:19",
                    "'position' must be a finite number within the range of 32-bit floats");
}

TEST_CASE("NUL bytes: in a description the compile succeeds: in source every diagnostic is printed", "[hostile]") {
    Bounded d = run_bounded(hostile("nul_description.iql") + " -o -");
    INFO(d.run.err);
    CHECK(d.run.exit_code == 0);
    CHECK_THAT(d.run.out, Catch::Contains("// r ∈ [0, 2]: before after"));
    Bounded s = run_bounded("eval " + hostile("nul_source.iql"));
    require_located(s, hostile("nul_source.iql") + ":1:7", "unexpected character '␀'");
    CHECK_THAT(s.run.err, Catch::Contains("  y = 1 ␀ 2\n"));
    CHECK_THAT(s.run.err, Catch::Contains(hostile("nul_source.iql") + ":2:5: error: undefined name 'q'"));
}

TEST_CASE("a 6-vector never reaches the emitter's swizzles: empty and path-like types are errors", "[hostile]") {
    require_located(run_bounded(hostile("six_vector.iql") + " -o -"), hostile("six_vector.iql") + ":2:1",
                    "cannot generate GLSL: ℝ⁶ is larger than GLSL's largest vector (vec4)");
    require_located(run_bounded(hostile("empty_type.iq") + " -o -"), hostile("empty_type.iq") + ":2:8",
                    "'type' cannot be empty");
    // A type is a module name, never a path: `../../stdlib/torus` exists as a file but is not found.
    require_located(run_bounded(hostile("path_type.iq") + " -o -"), hostile("path_type.iq") + ":2:8",
                    "unknown shape '../../stdlib/torus'");
    fs::path abs = generated("absolute.iq", "[[shapes]]\ntype = \"" + std::string(IQC_SOURCE_DIR) + "/stdlib/torus\"\n");
    require_located(run_bounded(abs.string() + " -o -"), abs.string() + ":2:8", "unknown shape");
    // Module names follow the same rule where they are defined: [modules] keys and ❤: lines.
    const std::string sphere = " = \"\"\"\nshape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n\"\"\"\n";
    // {TOML key, the name it reads as}
    for (auto [key, name] : std::vector<std::pair<std::string, std::string>>{{"a/b", "a/b"}, {"", ""}, {".hidden", ".hidden"},
                                                                             {"back\\\\slash", "back\\slash"}}) {
        fs::path m = generated("module_name.iq", "[modules]\n\"" + key + "\"" + sphere + "[[shapes]]\ntype = \"sphere\"\n");
        INFO(name);
        require_located(run_bounded(m.string() + " -o -"), m.string() + ":2:1", "'" + name + "' cannot name a module: a name is not empty");
    }
    // A declaration where a value goes (a shape parameter's string): a located error (it crashed).
    fs::path decl = generated("decl_value.iq", "[[shapes]]\ntype = \"sphere\"\nshape_params = { r = \"x ∈ ℝ\" }\n");
    require_located(run_bounded(decl.string() + " -o -"), decl.string() + ":3:22", "'r' must be a number, an array, or a constant expression");
    fs::path doc = generated("module_name.md", "❤: ../up\n```iheartla\nshape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n```\n");
    require_located(run_bounded(doc.string() + " -o -"), doc.string() + ":1:1", "'../up' cannot name a module");
}

TEST_CASE("property: every input of the fuzz corpora ends with exit 0 or 1 within 10 s and 2 GB", "[hostile][corpus]") {
    // The seed corpora of scripts/fuzz.sh (the project's modules, documents and scenes) and every regression
    // input the fuzzers found (tests/fuzz/HARNESS/): compiled for two targets, and module files evaluated as well.
    fs::path root = IQC_SOURCE_DIR;
    std::vector<fs::path> inputs;
    for (const char* dir : {"examples", "stdlib", "tests/hardcases", "tests/hostile", "golden/lang", "tests/fuzz/frontend",
                            "tests/fuzz/ir", "tests/fuzz/scene"}) {
        if (!fs::is_directory(root / dir)) continue;
        for (const auto& e : fs::directory_iterator(root / dir)) {
            std::string ext = e.path().extension().string();
            if (e.is_regular_file() && (ext == ".iq" || ext == ".iql" || ext == ".md")) inputs.push_back(e.path());
        }
    }
    std::sort(inputs.begin(), inputs.end());
    REQUIRE(inputs.size() > 100);
    for (const fs::path& in : inputs) {
        // Shadertoy (parameters as constants) and WebGL2 (as uniforms: K per cell of the sliders, the scene box at their
        // defaults; a recurrence's cells took 12× its Shadertoy compile, 10 s under ASan in the CI's fuzzing).
        std::vector<std::string> commands = {in.string() + " -o /dev/null", in.string() + " --target webgl2 -o /dev/null"};
        if (in.extension() == ".iql") commands.push_back("eval " + in.string());
        for (const std::string& args : commands) {
            Bounded b = run_bounded(args);
            INFO(args << "\nexit " << b.run.exit_code << "\n" << b.run.err.substr(0, 2000));
            CHECK((b.run.exit_code == 0 || b.run.exit_code == 1));
            if (b.run.exit_code == 1) CHECK_THAT(b.run.err, Catch::Contains("error"));
        }
    }
}

// Found by a new-user trial of issue 16 (hostile input), after the first fixes.

TEST_CASE("a depfile cannot inject Make rules: control characters are refused, ':' is escaped", "[hostile][depfile]") {
    fs::path dir = temp_dir() / "depfile_injection";
    fs::remove_all(dir);
    fs::create_directories(dir);
    std::string d = dir.string();
    std::ofstream(dir / "s.iq") << "[[shapes]]\ntype = \"sphere\"\n";
    // An output path with a newline and a recipe: refused before anything is written.
    Bounded out = run_bounded("'" + d + "/s.iq' -o '" + d + "/x.frag:\n\ttouch pwned\nz.frag' --depfile '" + d + "/s.d'");
    CHECK(out.run.exit_code == 1);
    CHECK_THAT(out.run.err, Catch::Contains("has a control character") && Catch::Contains("x.frag:\\n\\ttouch pwned\\nz.frag"));
    CHECK_FALSE(fs::exists(dir / "s.d"));
    CHECK_FALSE(fs::exists(d + "/x.frag:\n\ttouch pwned\nz.frag"));
    // An included module whose file name holds a newline and a recipe: the same.
    std::string evil = "m.iql\nall:\n\ttouch pwned\nZ=q.iql";
    std::ofstream(dir / evil) << "shape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n";
    std::ofstream(dir / "inc.iq") << "include = [\"m.iql\\nall:\\n\\ttouch pwned\\nZ=q.iql\"]\n[[shapes]]\ntype = \"sphere\"\n";
    Bounded inc = run_bounded("'" + d + "/inc.iq' -o '" + d + "/inc.frag' --depfile '" + d + "/inc.d'");
    CHECK(inc.run.exit_code == 1);
    CHECK_THAT(inc.run.err, Catch::Contains("cannot write the depfile"));
    CHECK_FALSE(fs::exists(dir / "inc.d"));
    CHECK_FALSE(fs::exists(dir / "inc.frag"));
    // A colon is escaped (GNU Make and Ninja read `\:`).
    fs::create_directories(dir / "a:b");
    std::ofstream(dir / "a:b" / "s.iq") << "[[shapes]]\ntype = \"sphere\"\n";
    Bounded colon = run_bounded("'" + d + "/a:b/s.iq' -o '" + d + "/c.frag' --depfile '" + d + "/c.d'");
    REQUIRE(colon.run.exit_code == 0);
    CHECK_THAT(read_text(dir / "c.d"), Catch::Contains("/a\\:b/s.iq"));
}

TEST_CASE("outputs that are devices are written in place, and write errors are errors", "[hostile]") {
    auto in = std::string(IQC_SOURCE_DIR) + "/examples/two_tori.md";
    // -o /dev/null must not replace the device with a regular file (a temporary file renamed over it would).
    Bounded b = run_bounded(in + " -o /dev/null --meta /dev/null");
    CHECK(b.run.exit_code == 0);
    struct stat st {};
    REQUIRE(stat("/dev/null", &st) == 0);
    CHECK(S_ISCHR(st.st_mode));
    // A full device, as an output file and as standard output: exit 1 with the reason, not a silent loss.
    Bounded full = run_bounded(in + " -o /dev/full");
    CHECK(full.run.exit_code == 1);
    CHECK_THAT(full.run.err, Catch::Contains("cannot write '/dev/full': No space left on device"));
    std::string cmd = std::string(IQC_BINARY) + " " + in + " > /dev/full 2>" + (temp_dir() / "full.err").string();
    int status = std::system(cmd.c_str());
    CHECK(WEXITSTATUS(status) == 1);
    CHECK_THAT(read_text(temp_dir() / "full.err"), Catch::Contains("cannot write standard output"));
    REQUIRE(stat("/dev/full", &st) == 0);
    CHECK(S_ISCHR(st.st_mode));
    // Outputs are all or none: a --meta that cannot be written leaves the shader (and the depfile) unwritten,
    // and an existing shader as it was.
    fs::path dir = temp_dir() / "all_or_none";
    fs::create_directories(dir);
    fs::remove(dir / "s.frag");
    Bounded meta = run_bounded(in + " -o " + (dir / "s.frag").string() + " --meta /dev/full --depfile " + (dir / "s.d").string());
    CHECK(meta.run.exit_code == 1);
    CHECK_THAT(meta.run.err, Catch::Contains("cannot write '/dev/full': No space left on device"));
    CHECK_FALSE(fs::exists(dir / "s.frag"));
    CHECK_FALSE(fs::exists(dir / "s.d"));
    CHECK_FALSE(fs::exists(dir / "s.frag.iqc-tmp"));
    std::ofstream(dir / "s.frag") << "old";
    CHECK(run_bounded(in + " -o " + (dir / "s.frag").string() + " --meta /dev/full").run.exit_code == 1);
    CHECK(read_text(dir / "s.frag") == "old");
    // The same compile with a meta that can be written writes both.
    Bounded ok = run_bounded(in + " -o " + (dir / "s.frag").string() + " --meta " + (dir / "s.json").string());
    CHECK(ok.run.exit_code == 0);
    CHECK(read_text(dir / "s.frag").rfind("// ", 0) == 0);
    CHECK(fs::exists(dir / "s.json"));
}

TEST_CASE("code that unrolls exponentially is a located error within the bounds", "[hostile]") {
    // f0(x) = f1(x) + f1(x), …, 60 deep: 2^60 copies once expanded.
    std::string text = "shape\n";
    for (int i = 0; i < 60; ++i) text += fmt::format("`f{}`(x) = `f{}`(x) + `f{}`(x)\n", i, i + 1, i + 1);
    text += "`f60`(x) = x\nD = `f0`(p_1)\nwhere\np ∈ ℝ³\nx ∈ ℝ\n";
    fs::path doubled = generated("doubled.iql", text);
    Bounded b = run_bounded(doubled.string() + " -o -");
    require_located(b, doubled.string() + ":", "this expands to more than 1000000 IR instructions in one function");
    // ∑_i ∑_j of a 4096-vector: 16.7 million terms.
    fs::path sums = generated("nested_sums.iql", "y = ∑_i ∑_j v_i v_j\nwhere\nv ∈ ℝ^4096\n");
    require_located(run_bounded("eval " + sums.string()), sums.string() + ":1:", "this expands to more than");
}

TEST_CASE("a min of 20,000 terms and a piecewise of 20,000 cases compile (no emitter recursion)", "[hostile]") {
    std::string args;
    for (int i = 0; i < 20000; ++i) args += fmt::format("{}p_{} - {}", i ? ", " : "", 1 + i % 3, i % 7);
    fs::path mm = generated("min20000.iql", "shape\nD = min(" + args + ")\nwhere\np ∈ ℝ³\n");
    Bounded a = run_bounded(mm.string() + " -o -");
    INFO(a.run.err.substr(0, 1000));
    CHECK(a.run.exit_code == 0);
    std::string cases;
    for (int i = 0; i < 20000; ++i) cases += fmt::format("{} if p_1 > {}\n", i % 5, 20000 - i);
    fs::path pw = generated("piecewise20000.iql", "shape\nD = ‖p‖ - r\nr = { " + cases + "1 otherwise\nwhere\np ∈ ℝ³\n");
    Bounded c = run_bounded(pw.string() + " -o -");
    INFO(c.run.err.substr(0, 1000));
    CHECK(c.run.exit_code == 0);
}

TEST_CASE("100,001 statements: one located error, and diagnostics stop at 200", "[hostile]") {
    std::string text = "shape\nD = ‖p‖ - 1\n";
    for (int i = 0; i < 100000; ++i) text += fmt::format("`a{}` = {}\n", i, i);
    text += "where\np ∈ ℝ³\n";
    fs::path many = generated("statements.iql", text);
    Bounded b = run_bounded(many.string() + " -o -");
    require_located(b, many.string() + ":", "a module has at most 100000 statements");
    std::string toml;
    for (int i = 0; i < 1000; ++i) toml += fmt::format("unknown_key_{} = 1\n", i);
    fs::path keys = generated("keys.iq", toml + "[[shapes]]\ntype = \"sphere\"\n");
    Bounded k = run_bounded(keys.string() + " -o -");
    CHECK(k.run.exit_code == 1);
    CHECK_THAT(k.run.err, Catch::Contains("more diagnostics not shown"));
    CHECK(k.run.err.size() < 200000);
}

TEST_CASE("long names, huge integers, NaN defaults and infinite bounds", "[hostile]") {
    // A 5,000-letter name (glslang refuses identifiers past 1,024 characters): cut and hashed.
    std::string name(5000, 'q');
    fs::path longname = generated("long_name.iq", "[[shapes]]\nname = \"" + name + "\"\ntype = \"sphere\"\n");
    Bounded l = run_bounded(longname.string() + " --target webgl2 -o -");
    INFO(l.run.err.substr(0, 500));
    CHECK(l.run.exit_code == 0);
    CHECK(glsl::identifier(name).size() <= glsl::kMaxIdentifier);
    CHECK(glsl::identifier(name) != glsl::identifier(name + "r"));
    CHECK(glsl::identifier("short_name") == "short_name");
    fs::path zbig = generated("zbig.iql", "shape\nD = ‖p‖ - n\nwhere\np ∈ ℝ³\nn ∈ ℤ default = 3000000000\n");
    require_located(run_bounded(zbig.string() + " -o -"), zbig.string() + ":5:17",
                    "the default of 'n' is 3000000000, not a 32-bit integer");
    fs::path zover = generated("zover.iq", "[modules]\nz = \"\"\"\nshape\nD = ‖p‖ - n\nwhere\np ∈ ℝ³\nn ∈ ℤ default = 1\n\"\"\"\n"
                                           "[[shapes]]\ntype = \"z\"\nshape_params = { n = 99999999999 }\n");
    require_located(run_bounded(zover.string() + " -o -"), zover.string() + ":11:18", "'n' is ℤ, but the value 99999999999 is not a 32-bit integer");
    fs::path nan = generated("nan_default.iql", "shape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\nr ∈ ℝ default = 0/0\n");
    require_located(run_bounded(nan.string() + " -o -"), nan.string() + ":5:17", "the default of 'r' is not a number");
    fs::path inf = generated("inf_bound.iql", "shape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\nr ∈ [0, 1/0] default = 1\n");
    require_located(run_bounded(inf.string() + " -o -"), inf.string() + ":5:5", "an interval bound must be a finite 32-bit float");
}

TEST_CASE("eval warns where acosh and atanh leave their domains, and x⁻¹⁻¹ is not read as x⁻¹", "[hostile]") {
    fs::path dom = generated("domains.iql", "y = acosh(x)\nz = atanh(x)\nacosh, atanh from trigonometry\nwhere\nx ∈ [0, 2]\n");
    Bounded d = run_bounded("eval " + dom.string() + " --set x=0.5");
    CHECK(d.run.exit_code == 0);
    CHECK_THAT(d.run.err, Catch::Contains(":1:1: warning: acosh of a value that can be below 1"));
    CHECK_THAT(d.run.err, Catch::Contains(":2:1: warning: atanh of a value that can reach ±1"));
    fs::path inv = generated("inv_twice.iql", "y = x⁻¹⁻¹\nwhere\nx ∈ ℝ\n");
    require_located(run_bounded("eval " + inv.string() + " --set x=2"), inv.string() + ":1:6",
                    "a superscript power is one integer such as ² or ⁻¹, not '⁻¹⁻¹'");
}

TEST_CASE("iqc bench of a scene too costly for the CPU reference falls back instead of failing", "[hostile][bench]") {
    fs::path rec = generated("bench_recurrence.iql", "shape\nz_1 = p\nz_(k+1) = z_k + (1,1,1) for k ∈ 1..100000000\n"
                                                     "D = ‖z_100000001‖ - 1\nwhere\np ∈ ℝ³\n");
    Bounded b = run_bounded("bench " + rec.string() + " --size 1x1 --frames 1");
    INFO(b.run.err.substr(0, 2000));
    CHECK(b.run.exit_code != 3);
    CHECK_THAT(b.run.err + b.run.out, !Catch::Contains("internal compiler error"));
}

// Found by a second new-user trial of issue 16.

TEST_CASE("a 10 MB line with errors: each diagnostic shows a window of the line", "[hostile]") {
    std::string line = "y = ";
    for (int i = 0; i < 200; ++i) line += fmt::format("`u{}` + ", i) + std::string(50000, ' ');
    line += "1";
    fs::path big = generated("long_line.iql", line + "\nwhere\nx ∈ ℝ\n");
    Bounded b = run_bounded("eval " + big.string());
    require_located(b, big.string() + ":1:", "undefined name 'u0'");
    CHECK(b.run.err.size() < 200000);  // not 200 copies of a 10 MB line
    CHECK_THAT(b.run.err, Catch::Contains("…"));
}

TEST_CASE("names that are GLSL macros, sequences read by local functions, huge TOML integers, tiny literals", "[hostile]") {
    fs::path gl = generated("GL_ES.iql", "shape\nD = ‖p‖ - `GL_ES`\nwhere\np ∈ ℝ³\n`GL_ES` ∈ ℝ default = 1\n");
    Bounded g = run_bounded(gl.string() + " -o -");
    INFO(g.run.err);
    CHECK(g.run.exit_code == 0);
    fs::path seq = generated("seq_local.iql", "shape\ng(y) = z_3 + y\nz_1 = 1\nz_(k+1) = z_k + 1 for k ∈ 1..2\nD = g(p_1)\n"
                                              "where\np ∈ ℝ³\ny ∈ ℝ\n");
    require_located(run_bounded(seq.string() + " -o -"), seq.string() + ":2:8", "the local function 'g' cannot read the sequence 'z'");
    fs::path bigint = generated("bigint.iq", "[modules]\nm = \"\"\"\nshape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\nr ∈ ℝ\n\"\"\"\n"
                                             "[[shapes]]\ntype = \"m\"\nshape_params = { r = 9007199254740993 }\n");
    Bounded bi = run_bounded(bigint.string() + " -o -");
    CHECK(bi.run.exit_code == 0);
    CHECK_THAT(bi.run.out, Catch::Contains("m_1_shape_r = 9007199000000000.0"));  // not 0.0
    fs::path tiny = generated("tiny.iql", "shape\nD = p_1 + 1e-400\nwhere\np ∈ ℝ³\n");
    require_located(run_bounded(tiny.string() + " -o -"), tiny.string() + ":2:11", "the number 1e-400 is below the smallest normal");
    fs::path cam = generated("camera_float.iq", "[camera]\nposition = [1, 0, 0]\ntarget = [1.00000001, 0, 0]\n[[shapes]]\ntype = \"sphere\"\n");
    require_located(run_bounded(cam.string() + " -o -"), cam.string() + ":1:1", "the camera's position and target are the same point in 32-bit floats");
    fs::path z = generated("zset.iql", "y = n + 1\nwhere\nn ∈ ℤ\n");
    Bounded zs = run_bounded("eval " + z.string() + " --set n=3000000000");
    CHECK(zs.run.exit_code == 1);
    CHECK_THAT(zs.run.err, Catch::Contains("is not a 32-bit integer"));
}

TEST_CASE("outputs may not be the input or each other, and render refuses silly sizes and times", "[hostile]") {
    fs::path dir = temp_dir() / "aliasing";
    fs::create_directories(dir);
    std::ofstream(dir / "s.iq") << "[[shapes]]\ntype = \"sphere\"\n";
    std::string s = (dir / "s.iq").string();
    Bounded self = run_bounded(s + " -o " + s);
    CHECK(self.run.exit_code == 2);
    CHECK_THAT(self.run.err, Catch::Contains("the input and -o are the same file"));
    CHECK_THAT(read_text(dir / "s.iq"), Catch::StartsWith("[[shapes]]"));  // not overwritten
    Bounded meta = run_bounded(s + " -o " + (dir / "x").string() + " --meta " + (dir / "x").string());
    CHECK(meta.run.exit_code == 2);
    Bounded both = run_bounded(s + " -o - --meta -");  // the shader and its JSON interleaved on standard output
    CHECK(both.run.exit_code == 2);
    CHECK_THAT(both.run.err, Catch::Contains("the shader goes to standard output: give --meta and --depfile a file"));
    Bounded pct = run_bounded(s + " -o '" + (dir / "o%.frag").string() + "' --depfile " + (dir / "d.d").string());
    CHECK(pct.run.exit_code == 1);
    CHECK_THAT(pct.run.err, Catch::Contains("cannot write the depfile"));
    Bounded size = run_bounded("render " + s + " -o " + (dir / "r.png").string() + " --size 8193x8193");
    CHECK(size.run.exit_code == 2);
    CHECK_THAT(size.run.err, Catch::Contains("too large"));
    Bounded junk = run_bounded("render " + s + " -o " + (dir / "r.png").string() + " --size 8x8junk");
    CHECK(junk.run.exit_code == 2);
    Bounded nan = run_bounded("render " + s + " -o " + (dir / "r.png").string() + " --size 8x8 --time nan");
    CHECK(nan.run.exit_code == 2);
    Bounded huge = run_bounded("bench " + s + " --size 5000x5000");  // ran for hours (a new user's trial)
    CHECK(huge.run.exit_code == 2);
    CHECK_THAT(huge.run.err, Catch::Contains("--size 5000x5000 is too large for bench: at most 1920x1080 pixels"));
}

TEST_CASE("no output replaces a file the command reads: the scene, a module it includes, a rendered shader", "[hostile]") {
    // Found by a new user's trial: only `iqc X -o X` was refused; `render scene.iq -o scene.iq` replaced the
    // scene with its PNG, `-o` onto an included module replaced it with the shader, `bench --csv` onto the
    // scene replaced it with the table.
    fs::path dir = temp_dir() / "clobber";
    fs::create_directories(dir);
    const std::string module = "shape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n";
    const std::string scene = "include = [\"ball.iql\"]\n[[shapes]]\ntype = \"ball\"\n";
    std::ofstream(dir / "ball.iql") << module;
    std::ofstream(dir / "s.iq") << scene;
    std::ofstream(dir / "h.frag") << "void mainImage(out vec4 c, in vec2 f) { c = vec4(1.0); }\n";
    std::string s = (dir / "s.iq").string(), m = (dir / "ball.iql").string(), h = (dir / "h.frag").string();
    struct Case {
        std::string args, flag, out;
    };
    for (const Case& c : {Case{"render " + s + " --size 8x8 -o " + s, "-o", s}, Case{s + " -o " + m, "-o", m},
                          Case{s + " -o " + (dir / "x.frag").string() + " --meta " + m, "--meta", m},
                          Case{"render " + s + " --size 8x8 -o " + m, "-o", m}, Case{"render " + h + " --size 8x8 -o " + h, "-o", h},
                          Case{"bench " + s + " --size 8x8 --csv " + s, "--csv", s}}) {
        Bounded r = run_bounded(c.args);
        INFO(c.args << "\n" << r.run.err);
        CHECK(r.run.exit_code == 2);
        CHECK_THAT(r.run.err, Catch::Contains("iqc: error: " + c.flag + " '" + c.out + "' is a file this command reads"));
    }
    CHECK(read_text(dir / "ball.iql") == module);
    CHECK(read_text(dir / "s.iq") == scene);
    CHECK_THAT(read_text(dir / "h.frag"), Catch::StartsWith("void mainImage"));
    // A new output beside them is written as before.
    CHECK(run_bounded("render " + s + " --size 8x8 -q -o " + (dir / "s.png").string()).run.exit_code == 0);
    // bench --replot (a second trial: --plot onto the scene, a module or the CSV became an SVG) and --csv and
    // --plot onto one file (refused only after the whole bench) are refused before anything runs.
    std::ofstream(dir / "r.csv") << "method,hit,max_steps,normals,frame_ms,evals_per_pixel_mean,evals_per_pixel_p99,hit_mismatch_pct,"
                                    "depth_err_p99,normal_err_deg_p99,psnr_db\nsphere,0.001,64,tetrahedron,1,2,3,0,0,0,50\n";
    std::string csv = (dir / "r.csv").string(), both = (dir / "both.csv").string();
    for (const Case& c : {Case{"bench " + s + " --replot " + csv + " --plot " + s, "--plot", s},
                          Case{"bench " + s + " --replot " + csv + " --plot " + m, "--plot", m},
                          Case{"bench " + s + " --replot " + csv + " --plot " + csv, "--plot", csv}}) {
        Bounded r = run_bounded(c.args);
        INFO(c.args << "\n" << r.run.err);
        CHECK(r.run.exit_code == 2);
        CHECK_THAT(r.run.err, Catch::Contains("iqc: error: " + c.flag + " '" + c.out + "' is a file this command reads"));
    }
    Bounded same = run_bounded("bench " + s + " --size 8x8 --csv " + both + " --plot " + both);
    CHECK(same.run.exit_code == 2);
    CHECK_THAT(same.run.err, Catch::Contains("--csv and --plot are the same file"));
    CHECK(read_text(dir / "s.iq") == scene);
    CHECK(read_text(dir / "ball.iql") == module);
    // Frames are numbered before the file name's extension, not the path's last dot, and render writes no '-'.
    fs::create_directories(dir / "v1.2");
    CHECK(run_bounded("render " + s + " --size 8x8 -q --frames 2 -o " + (dir / "v1.2" / "x").string()).run.exit_code == 0);
    CHECK(fs::exists(dir / "v1.2" / "x_0000.png"));
    CHECK(fs::exists(dir / "v1.2" / "x_0001.png"));
    Bounded dash = run_bounded("render " + s + " --size 8x8 -o -");
    CHECK(dash.run.exit_code == 2);
    CHECK_THAT(dash.run.err, Catch::Contains("render writes PNG files"));
    Bounded late = run_bounded("render " + s + " --size 8x8 --frames 2 --fps 1e-38 --time 3e38 -o " + (dir / "late.png").string());
    CHECK(late.run.exit_code == 2);
    CHECK_THAT(late.run.err, Catch::Contains("past 32-bit floats"));
}

TEST_CASE("long titles and names are capped, and eval's --time and --mouse are checked as render's are", "[hostile]") {
    // Found by a new-user trial: a 3 MB title made a 6 MB HTML page, a 5 MB instance name a 10 MB shader; eval
    // took --time nan and --mouse 1e40, and render's --fps 0 printed a range ending in a 300-digit number.
    fs::path title = generated("long_title.iq", "title = \"" + std::string(1001, 't') + "\"\n[[shapes]]\ntype = \"sphere\"\n");
    require_located(run_bounded(title.string() + " -o -"), title.string() + ":1:9", "the title has 1001 bytes: at most 1000");
    fs::path name = generated("long_name.iq", "[[shapes]]\nname = \"" + std::string(8193, 'n') + "\"\ntype = \"sphere\"\n");
    require_located(run_bounded(name.string() + " -o -"), name.string() + ":2:8", "an instance name has 8193 bytes: at most 8192");
    fs::path light = generated("long_light.iq", "[[lights]]\nname = \"" + std::string(9000, 'l') + "\"\nposition = [1, 2, 3]\n"
                                                "[[shapes]]\ntype = \"sphere\"\n");
    require_located(run_bounded(light.string() + " -o -"), light.string() + ":2:8", "a light's name has 9000 bytes: at most 8192");
    fs::path ok = generated("fine_title.iq", "title = \"" + std::string(1000, 't') + "\"\n[[shapes]]\ntype = \"sphere\"\n");
    CHECK(run_bounded(ok.string() + " -o -").run.exit_code == 0);
    std::string sphere = (fs::path(IQC_SOURCE_DIR) / "stdlib" / "sphere.iql").string();
    Bounded tnan = run_bounded("eval " + sphere + " --set 'p=(1,0,0)' --time nan");
    CHECK(tnan.run.exit_code == 2);
    CHECK_THAT(tnan.run.err, Catch::Contains("--time must be a finite number"));
    Bounded mouse = run_bounded("eval " + sphere + " --set 'p=(1,0,0)' --mouse 1e40 0");
    CHECK(mouse.run.exit_code == 2);
    CHECK_THAT(mouse.run.err, Catch::Contains("--mouse takes two numbers in [0, 1]"));
    CHECK(run_bounded("eval " + sphere + " --set 'p=(1,0,0)' --mouse 0.5 1 --time 2").run.exit_code == 0);
    Bounded fps = run_bounded("render " + ok.string() + " -o " + (temp_dir() / "fps.png").string() + " --size 8x8 --frames 2 --fps 0");
    CHECK(fps.run.exit_code == 2);
    CHECK_THAT(fps.run.err, Catch::Contains("--fps: must be a number of frames per second in (0, 1e6]"));
}

TEST_CASE("many lights and long descriptions are capped", "[hostile]") {
    std::string lights;
    for (int i = 0; i < 300; ++i) lights += fmt::format("[[lights]]\nposition = [{}, 5, 0]\n", i);
    fs::path many = generated("lights.iq", lights + "[[shapes]]\ntype = \"sphere\"\nmaterial = \"lambert\"\n");
    require_located(run_bounded(many.string() + " -o -"), many.string() + ":", "a scene has at most 256 lights");
    fs::path desc = generated("description.iql", "shape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\nr ∈ [0, 1] default = 0.5: " + std::string(5000, 'd') + "\n");
    require_located(run_bounded(desc.string() + " -o -"), desc.string() + ":5:1", "the description of 'r' has 5000 bytes");
}

TEST_CASE("5,000 chained statements with analytic normals: names are handed out in linear time", "[hostile]") {
    std::string chain = "shape\nsin from trigonometry\n";
    for (int i = 0; i < 5000; ++i) chain += fmt::format("`a{}` = sin(`a{}`) ⋅ `a{}` + p_2\n", i, i + 1, i + 1);
    chain += "`a5000` = p_1\nD = `a0`\nwhere\np ∈ ℝ³\n";
    generated("chain.iql", chain);
    fs::path scene = generated("chain_analytic.iq", "include = [\"chain.iql\"]\n[render]\nnormals = \"analytic\"\n[[shapes]]\ntype = \"chain\"\n");
    Bounded b = run_bounded(scene.string() + " -o /dev/null");  // 17 s before (Namer probed tmp_2, tmp_3, … each time)
    INFO(b.run.err.substr(0, 1000));
    CHECK(b.run.exit_code == 0);
}
