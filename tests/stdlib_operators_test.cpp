// The standard library's operators, domain and noise modules at their limits, through `iqc eval` (which
// finds stdlib modules): smooth operators at k = 0 and k → 0 equal the plain ones, the exponential
// smooth minimum stays finite for tiny k and large distances, chamfer and stairs reduce to min at size 0,
// repetition is periodic, noise stays within its documented range and is deterministic. Also: every new
// material, fractal and terrain module compiles for every target inside a scene.
#include <catch2/catch.hpp>
#include <cmath>
#include <fmt/format.h>
#include <random>

#include "TestUtil.h"
#include "ir/passes/Lipschitz.h"

using namespace iqc::test;

namespace {

// Runs `iqc eval` on a module text with NAME=VALUE settings; returns NAME → printed value text.
std::map<std::string, std::string> eval_text(const std::string& file, const std::string& text,
                                             const std::vector<std::pair<std::string, std::string>>& set) {
    auto path = write_temp(file, text);
    std::string args = "eval '" + path.string() + "'";
    for (auto& [n, v] : set) args += " --set '" + n + "=" + v + "'";
    RunResult r = run_iqc(args);
    INFO(args << "\n" << r.err);
    REQUIRE(r.exit_code == 0);
    std::map<std::string, std::string> out;
    std::istringstream in(r.out);
    std::string line;
    while (std::getline(in, line)) {
        auto eq = line.find(" = ");
        if (eq != std::string::npos) out[line.substr(0, eq)] = line.substr(eq + 3);
    }
    return out;
}

double num(const std::map<std::string, std::string>& m, const std::string& name) {
    auto it = m.find(name);
    REQUIRE(it != m.end());
    return std::stod(it->second);
}

std::vector<double> vec(const std::map<std::string, std::string>& m, const std::string& name) {
    auto it = m.find(name);
    REQUIRE(it != m.end());
    std::string s = it->second;
    for (char& c : s)
        if (c == '(' || c == ')' || c == ',') c = ' ';
    std::istringstream in(s);
    std::vector<double> v;
    double x;
    while (in >> x) v.push_back(x);
    return v;
}

std::string fmt3(double x, double y, double z) {
    std::ostringstream s;
    s.precision(17);
    s << "(" << x << "," << y << "," << z << ")";
    return s.str();
}

std::string num_text(double x) {
    std::ostringstream s;
    s.precision(17);
    s << x;
    return s.str();
}

const char* kOperators =
    "union, intersection, subtraction, xor, `smooth_union`, `smooth_intersection`, `smooth_subtraction`, "
    "`smooth_union_exp`, `chamfer_union`, `stairs_union`, round, onion, displace from operators\n"
    "u = union(a, b)\n"
    "`i_` = intersection(a, b)\n"
    "s = subtraction(a, b)\n"
    "x = xor(a, b)\n"
    "`su` = `smooth_union`(a, b, k)\n"
    "`si` = `smooth_intersection`(a, b, k)\n"
    "`ss` = `smooth_subtraction`(a, b, k)\n"
    "`se` = `smooth_union_exp`(a, b, k)\n"
    "`cu` = `chamfer_union`(a, b, k)\n"
    "`st` = `stairs_union`(a, b, k, 5)\n"
    "r = round(a, k)\n"
    "o = onion(a, k)\n"
    "d = displace(a, k)\n"
    "where\n"
    "a ∈ ℝ\n"
    "b ∈ ℝ\n"
    "k ∈ ℝ\n";

}  // namespace

TEST_CASE("operators: the plain operations", "[stdlib][operators]") {
    auto m = eval_text("use_operators.iql", kOperators, {{"a", "0.3"}, {"b", "-0.5"}, {"k", "0.25"}});
    CHECK(num(m, "u") == -0.5);
    CHECK(num(m, "i_") == 0.3);
    CHECK(num(m, "s") == Approx(-0.3).margin(1e-15));  // b minus a: max(-a, b)
    CHECK(num(m, "x") == Approx(-0.3).margin(1e-15));  // xor: max(min, -max)
    CHECK(num(m, "r") == Approx(0.05).margin(1e-15));
    CHECK(num(m, "o") == Approx(0.05).margin(1e-15));
    CHECK(num(m, "d") == Approx(0.55).margin(1e-15));
}

TEST_CASE("operators: smooth, chamfer and stairs reduce to the plain operation at size 0 and 1e-9", "[stdlib][operators]") {
    const std::vector<std::pair<double, double>> ab = {{0.3, 0.5}, {-0.2, 0.7}, {1.5, -2}, {1e3, -1e3}, {-4, -4.5}, {0.25, 0.25}, {0, 0}};
    for (double k : {0.0, 1e-9}) {
        for (auto [a, b] : ab) {
            auto m = eval_text("use_operators.iql", kOperators, {{"a", num_text(a)}, {"b", num_text(b)}, {"k", num_text(k)}});
            INFO("a = " << a << ", b = " << b << ", k = " << k);
            double mn = std::min(a, b), mx = std::max(a, b), sub = std::max(-a, b);
            // The quadratic kernel lowers the surface by at most k/4, only where |a - b| < k.
            double tol = (k == 0 || std::fabs(a - b) >= k) ? 0 : k / 4 + 1e-12;
            double tol_sub = (k == 0 || std::fabs(a + b) >= k) ? 0 : k / 4 + 1e-12;
            if (k == 0) {
                CHECK(num(m, "su") == mn);
                CHECK(num(m, "si") == mx);
                CHECK(num(m, "ss") == sub);
                CHECK(num(m, "se") == mn);
                CHECK(num(m, "cu") == mn);
                CHECK(num(m, "st") == mn);
            } else {
                CHECK(std::fabs(num(m, "su") - mn) <= std::max(tol, 1e-12));
                CHECK(std::fabs(num(m, "si") - mx) <= std::max(tol, 1e-12));
                CHECK(std::fabs(num(m, "ss") - sub) <= std::max(tol_sub, 1e-12));
                CHECK(std::fabs(num(m, "se") - mn) <= k * std::log(2.0) + 1e-12);
                CHECK(std::fabs(num(m, "cu") - mn) <= k + 1e-12);
                CHECK(std::fabs(num(m, "st") - mn) <= k + 1e-12);
            }
        }
    }
}

TEST_CASE("operators: negative sizes behave as 0: smooth ops stay between min - k/4 and min", "[stdlib][operators]") {
    auto m = eval_text("use_operators.iql", kOperators, {{"a", "0.1"}, {"b", "0.2"}, {"k", "-0.5"}});
    CHECK(num(m, "su") == 0.1);
    CHECK(num(m, "se") == 0.1);
    CHECK(num(m, "cu") == 0.1);
    CHECK(num(m, "st") == 0.1);
    auto n = eval_text("use_operators.iql", kOperators, {{"a", "0.1"}, {"b", "0.2"}, {"k", "0.5"}});
    CHECK(num(n, "su") < 0.1);
    CHECK(num(n, "su") >= 0.1 - 0.5 / 4);
    CHECK(num(n, "si") > 0.2);
    CHECK(num(n, "si") <= 0.2 + 0.5 / 4);
    CHECK(num(n, "se") < 0.1);
    CHECK(num(n, "se") >= 0.1 - 0.5 * std::log(2.0) - 1e-12);
    CHECK(num(n, "cu") <= 0.1);
    CHECK(num(n, "st") <= 0.1);
}

TEST_CASE("operators: the exponential smooth minimum never overflows", "[stdlib][operators]") {
    for (auto [a, b, k] : std::vector<std::array<double, 3>>{{1e3, -1e3, 1e-6}, {-1e3, 1e3, 1e-6}, {1e3, 1e3, 1e-6}, {-1e3, -1e3, 1e-6},
                                                            {1e3, 0.5, 1e-6}, {3e4, -2e4, 1e-3}, {0.3, 0.3, 1e-6}}) {
        auto m = eval_text("use_operators.iql", kOperators, {{"a", num_text(a)}, {"b", num_text(b)}, {"k", num_text(k)}});
        INFO("a = " << a << ", b = " << b << ", k = " << k);
        double se = num(m, "se");
        CHECK(std::isfinite(se));
        CHECK(se <= std::min(a, b));
        CHECK(se >= std::min(a, b) - k * std::log(2.0) - 1e-9);
    }
}

TEST_CASE("domain: repetition is periodic, limited repetition stops, symmetry and revolution", "[stdlib][domain]") {
    const char* mod =
        "repeat, `repeat_limited`, `repeat_angular`, mirror, `mirror_xz`, elongate, extrude, revolve, twist, bend from domain\n"
        "a = repeat(q, (1, 2, 3))\n"
        "b = `repeat_limited`(q, (1, 1, 1), (1, 1, 1))\n"
        "c = `repeat_angular`(q, 6)\n"
        "m = mirror(q)\n"
        "n = `mirror_xz`(q)\n"
        "e = elongate(q, (0.5, 0.5, 0.5))\n"
        "x = extrude(-0.2, q_3, 0.5)\n"
        "r = revolve(q, 1)\n"
        "t = twist(q, 0)\n"
        "g = bend(q, 0)\n"
        "where\n"
        "q ∈ ℝ³\n";
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(-3, 3);
    for (int i = 0; i < 8; ++i) {
        double x = u(rng), y = u(rng), z = u(rng);
        auto m0 = eval_text("use_domain.iql", mod, {{"q", fmt3(x, y, z)}});
        auto m1 = eval_text("use_domain.iql", mod, {{"q", fmt3(x + 2, y - 4, z + 9)}});  // whole periods
        auto a0 = vec(m0, "a"), a1 = vec(m1, "a");
        REQUIRE(a0.size() == 3);
        for (int c = 0; c < 3; ++c) CHECK(a0[size_t(c)] == Approx(a1[size_t(c)]).margin(1e-9));
        // The cell around the origin: |a_i| ≤ c_i / 2.
        CHECK(std::fabs(a0[0]) <= 0.5 + 1e-12);
        CHECK(std::fabs(a0[1]) <= 1 + 1e-12);
        CHECK(std::fabs(a0[2]) <= 1.5 + 1e-12);
        // Angular repetition: the same radius and height, the angle within ±π/6 of +x; rotating the point
        // by a whole sector gives the same result.
        auto c0 = vec(m0, "c");
        CHECK(std::hypot(c0[0], c0[2]) == Approx(std::hypot(x, z)).margin(1e-9));
        CHECK(c0[1] == Approx(y).margin(1e-12));
        CHECK(std::fabs(std::atan2(c0[2], c0[0])) <= M_PI / 6 + 1e-9);
        double th = M_PI / 3;
        auto mr = eval_text("use_domain.iql", mod, {{"q", fmt3(x * std::cos(th) - z * std::sin(th), y, x * std::sin(th) + z * std::cos(th))}});
        auto cr = vec(mr, "c");
        for (int c = 0; c < 3; ++c) CHECK(cr[size_t(c)] == Approx(c0[size_t(c)]).margin(1e-9));
        // Twist and bend by 0 are the identity.
        auto t = vec(m0, "t"), g = vec(m0, "g");
        CHECK(t[0] == Approx(x).margin(1e-12));
        CHECK(t[2] == Approx(z).margin(1e-12));
        CHECK(g[0] == Approx(x).margin(1e-12));
        CHECK(g[1] == Approx(y).margin(1e-12));
    }
    // Limited repetition: beyond the last copy the point is not folded back any more.
    auto far = eval_text("use_domain.iql", mod, {{"q", "(5.2, 0.3, -7.4)"}});
    auto b = vec(far, "b");
    CHECK(b[0] == Approx(4.2).margin(1e-12));
    CHECK(b[1] == Approx(0.3).margin(1e-12));
    CHECK(b[2] == Approx(-6.4).margin(1e-12));
    auto mm = vec(far, "m"), nn = vec(far, "n"), e = vec(far, "e"), r = vec(far, "r");
    CHECK(mm[0] == 5.2);
    CHECK(mm[2] == -7.4);
    CHECK(nn[2] == 7.4);
    CHECK(e[0] == Approx(4.7).margin(1e-12));
    CHECK(e[2] == Approx(-6.9).margin(1e-12));
    CHECK(r[0] == Approx(std::hypot(5.2, 7.4) - 1).margin(1e-12));
    CHECK(r[1] == 0.3);
    CHECK(num(far, "x") == Approx(6.9).margin(1e-12));  // |z| - h outside the slab, the 2D part inside
}

TEST_CASE("noise: every field stays within its documented range and is deterministic", "[stdlib][noise]") {
    const char* mod =
        "hash, `hash3`, `value_noise`, `value_noise2`, `gradient_noise`, `simplex_noise`, fbm, `fbm2` from noise\n"
        "h = hash(q)\n"
        "`h_3` = `hash3`(q)\n"
        "v = `value_noise`(q)\n"
        "w = `value_noise2`((q_1, q_3))\n"
        "g = `gradient_noise`(q)\n"
        "s = `simplex_noise`(q)\n"
        "f = fbm(q)\n"
        "`f_2` = `fbm2`((q_1, q_3))\n"
        "where\n"
        "q ∈ ℝ³\n";
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> u(-40, 40);
    double smin = 1, smax = -1, gmin = 1, gmax = -1;
    for (int i = 0; i < 150; ++i) {
        std::string q = fmt3(u(rng), u(rng), u(rng));
        auto m = eval_text("use_noise.iql", mod, {{"q", q}});
        INFO("q = " << q);
        CHECK(num(m, "h") >= 0);
        CHECK(num(m, "h") < 1);
        for (double c : vec(m, "h_3")) {
            CHECK(c >= 0);
            CHECK(c < 1);
        }
        CHECK(num(m, "v") >= 0);
        CHECK(num(m, "v") <= 1);
        CHECK(num(m, "w") >= 0);
        CHECK(num(m, "w") <= 1);
        CHECK(std::fabs(num(m, "g")) <= std::sqrt(3.0) / 2);
        CHECK(std::fabs(num(m, "s")) <= 1);
        CHECK(std::fabs(num(m, "f")) <= 15.0 / 16);
        CHECK(std::fabs(num(m, "f_2")) <= 15.0 / 16);
        smin = std::min(smin, num(m, "s"));
        smax = std::max(smax, num(m, "s"));
        gmin = std::min(gmin, num(m, "g"));
        gmax = std::max(gmax, num(m, "g"));
        if (i % 25 == 0) {
            auto again = eval_text("use_noise.iql", mod, {{"q", q}});
            CHECK(again == m);
        }
    }
    // Not constant: the fields vary over the samples.
    CHECK(smax - smin > 0.1);
    CHECK(gmax - gmin > 0.3);
    // Gradient noise is 0 at lattice points.
    auto lattice = eval_text("use_noise.iql", mod, {{"q", "(3, -2, 7)"}});
    CHECK(std::fabs(num(lattice, "g")) < 1e-12);
}

TEST_CASE("stdlib materials, fractals and the terrain compile for every target", "[stdlib]") {
    std::string scene =
        "[modules]\nball = \"\"\"\nshape\nD = ‖p‖ - 0.4\nwhere\np ∈ ℝ³\n\"\"\"\n"
        "[effects]\nshadows = \"soft\"\nreflections = 1\nrefraction = true\n"
        "[[lights]]\nposition = [-4, 6, -3]\n";
    int x = 0;
    for (const char* mat : {"lambert", "phong", "blinn_phong", "toon", "normal_color", "checker", "mirror", "glass", "emissive"})
        scene += "[[shapes]]\ntype = \"ball\"\nmaterial = \"" + std::string(mat) + "\"\ntransform = \"T((" + std::to_string(x++) + ", 0, 5))\"\n";
    for (const char* shape : {"menger", "mandelbulb", "terrain"})
        scene += "[[shapes]]\ntype = \"" + std::string(shape) + "\"\nmaterial = \"lambert\"\ntransform = \"T((" + std::to_string(x++) + ", 0, 5))\"\n";
    auto path = write_temp("stdlib_all.iq", scene);
    for (const char* target : {"shadertoy", "webgl2", "glsl330"}) {
        RunResult r = run_iqc("'" + path.string() + "' --target " + target + " -o /dev/null");
        INFO(target << "\n" << r.err);
        CHECK(r.exit_code == 0);
    }
}

TEST_CASE("each combinator's Lipschitz factor holds: |∂F/∂a| + |∂F/∂b| by finite differences", "[stdlib]") {
    // The Lipschitz pass bounds a smooth union's gradient by its factor times the larger of its operands'
    // (ir::combinator_factor); the factor rests on |∂F/∂a| + |∂F/∂b| ≤ factor. Central differences at random
    // distances, with radii from 0.01 to 2 and points near a = b (where the blends act) and far from it.
    const std::vector<std::string> ops = {"union", "intersection", "subtraction", "smooth_union", "smooth_intersection",
                                          "smooth_subtraction", "smooth_union_exp", "chamfer_union"};
    std::string text;
    for (size_t i = 0; i < ops.size(); ++i) text += (i ? ", " : "") + ("`" + ops[i] + "`");
    text += " from operators\n";
    for (const auto& op : ops) {
        std::string r = op.find('_') == std::string::npos ? ")" : ", k)";  // union(a, b); smooth_union(a, b, k)
        auto F = [&](const std::string& a, const std::string& b) { return "`" + op + "`(" + a + ", " + b + r; };
        text += "`s_" + op + "` = (|" + F("a + h", "b") + " - " + F("a - h", "b") + "| + |" + F("a", "b + h") + " - " + F("a", "b - h") +
                "|)/(2h)\n";
    }
    text += "where\na ∈ ℝ\nb ∈ ℝ\nk ∈ ℝ\nh ∈ ℝ\n";
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 1);
    std::map<std::string, double> worst;
    for (int s = 0; s < 24; ++s) {
        double k = 0.01 + 2 * u(rng) * u(rng), a = 4 * u(rng) - 2;
        double b = a + (s % 2 ? (2 * u(rng) - 1) * 1.5 * k : 8 * u(rng) - 4);
        auto out = eval_text("combinator_factors.iql", text,
                             {{"a", fmt::format("{:.17g}", a)}, {"b", fmt::format("{:.17g}", b)}, {"k", fmt::format("{:.17g}", k)}, {"h", "1e-6"}});
        for (const auto& op : ops) worst[op] = std::max(worst[op], num(out, "s_" + op));
    }
    for (const auto& op : ops) {
        double factor = iqc::ir::combinator_factor("operators." + op);
        INFO(op << ": the largest |∂F/∂a| + |∂F/∂b| sampled is " << worst[op] << ", the factor " << factor);
        CHECK(factor >= 1);
        CHECK(worst[op] <= factor * (1 + 1e-4));
        CHECK(worst[op] >= 0.99);  // the samples reach the factor's regime (each is at least a min's 1)
    }
    CHECK(worst["chamfer_union"] > 1.3);  // its bevel, (a + b - r)/√2, was sampled
    CHECK(iqc::ir::combinator_factor("operators.stairs_union") == 0);  // not claimed
}
