// Instancing: many instances of one shape with one material are one loop over per-instance data, one case
// of each dispatch, on every target; and they draw what the double-precision reference (SceneModel, the
// same IR run by the evaluator) says: the same instance at the same depth, through both `iqc render`
// targets (Shadertoy constants; webgl2 uniform blocks or the data texture).
#include <catch2/catch.hpp>

#include <map>
#include <set>

#include <cmath>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "TestUtil.h"
#include "ir/Eval.h"
#include "scene/Reference.h"

using namespace iqc;
using namespace iqc::test;

namespace {

// A ground and n rings on a grid of layers, each with its own constant transform. `irregular`: the rings
// are jittered and tilted about two axes (their tables stay tables: no lattice, and a whole matrix per ring,
// not the few entries of a tilt about one axis), else they sit on a regular grid. `bound`:
// each ring's bounding radius (0: none).
std::string rings_scene(int n, bool irregular, double bound = 0) {
    std::string s =
        "title = \"rings\"\n[modules]\nring = \"\"\"\nshape\nD = ‖q‖ - t_2\nq = (‖(p_1, p_3)‖ - t_1, p_2)\nwhere\np ∈ ℝ³\n"
        "t ∈ [0,2]x[0,2] default = (0.3, 0.08)\n\"\"\"\nground = \"\"\"\nshape\nD = p_2 + h\nwhere\np ∈ ℝ³\nh ∈ [0,5] default = 1\n\"\"\"\n"
        "lambert = \"\"\"\nmaterial\nC = max(0, L̂⋅N̂)`k_d` + 0.05`k_d`\nL̂ = (`P_L` - p)/‖`P_L` - p‖\nwhere\np ∈ ℝ³\nN̂ ∈ ℝ³\nI ∈ ℝ³\n"
        "`P_L` ∈ ℝ³\n`k_d` ∈ [0,1]x[0,1]x[0,1] default = (0.8, 0.5, 0.2)\n\"\"\"\n"
        "[camera]\nposition = [0, 7, -13]\ntarget = [0, 0, 0]\n[[lights]]\nposition = [-5, 8, -6]\n"
        "[[shapes]]\ntype = \"ground\"\nmaterial = \"lambert\"\nmaterial_params = { k_d = [0.5, 0.5, 0.5] }\n";
    int side = 1;
    while (side * side * 10 < n) ++side;
    uint32_t h = 12345;
    auto rnd = [&] {  // deterministic jitter in [-0.5, 0.5)
        h = h * 1664525u + 1013904223u;
        return double(h >> 8) / double(1u << 24) - 0.5;
    };
    for (int i = 0; i < n; ++i) {
        double x = (i % side) - side / 2.0, z = (i / side) % side - side / 2.0, y = (i / (side * side)) * 0.5 - 0.7;
        std::string t;
        // (The tilts are jittered too: cycling through 7 angles, the matrix table would keep one period.)
        if (irregular) t = fmt::format("T(({:.4f}, {:.4f}, {:.4f}))⋅`R_y`(0.3)⋅`R_x`({:.3f})", x + 0.3 * rnd(), y, z + 0.3 * rnd(), 0.4 * (i % 7) + 0.2 * rnd());
        else t = fmt::format("T(({}, {}, {}))", x, y, z);
        s += fmt::format("[[shapes]]\ntype = \"ring\"\nmaterial = \"lambert\"\ntransform = \"{}\"\n", t);
        if (bound > 0) s += fmt::format("bound = {}\n", bound);
    }
    return s;
}

// Compares the rendered ids and depths (an `ids` render) with the double-precision reference at every
// `step`-th pixel from (1, 1): how many samples, how many disagree, how many show a ring (id ≥ 1).
struct Agreement {
    int samples = 0, disagree = 0, rings = 0;
};
Agreement against_reference(const CompileResult& c, const render::RenderResult& r, int W, int H, int step) {
    const SceneModel& model = *c.model;
    Agreement a;
    for (int y = 1; y < H; y += step)
        for (int x = 1; x < W; x += step) {
            std::array<double, 3> ro, rd;
            model.ray(x, y, W, H, ro, rd);
            int id = -1;
            double tm = model.trace(ro, rd, &id);
            const float* px = r.image.pixel(x, y);
            int gid = int(std::lround(px[1]));
            ++a.samples;
            a.rings += gid >= 1;
            bool same = gid == id && (id < 0 || std::fabs(px[0] - tm) <= 1e-2 * std::max(1.0, tm));
            if (!same) {
                ++a.disagree;
                UNSCOPED_INFO(fmt::format("pixel ({}, {}): shader id {} at {}, reference id {} at {}", x, y, gid, px[0], id, tm));
            }
        }
    return a;
}

// Compiles `text` for an `ids` render (per pixel the depth and the instance id: against_reference).
Compiled compile_ids(const std::string& name, const std::string& text) {
    CompileOptions o;
    o.ids = true;
    return compile_path(write_temp(name, text), o);
}

int count(const std::string& s, const std::string& what) {
    int n = 0;
    for (size_t at = s.find(what); at != std::string::npos; at = s.find(what, at + 1)) ++n;
    return n;
}

// Scene evaluations and shape evaluations in all over a W×H picture of the scene at `path` compiled with
// `o` and the instrumentation (the counts `iqc render --stats` prints).
struct Evaluations {
    double evals = 0, shapes = 0;
};
Evaluations count_evaluations(const std::filesystem::path& path, CompileOptions o, int W, int H) {
    o.ids = false;
    o.instrument = true;
    Compiled ic = compile_path(path, o);
    REQUIRE(ic.result.exit_code == 0);
    render::RenderResult ir = render_compiled(ic.result, W, H);
    INFO(ir.error);
    REQUIRE(ir.ok);
    Evaluations n;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            n.evals += ir.image.pixel(x, y)[1];
            n.shapes += ir.image.pixel(x, y)[3];
        }
    return n;
}

// Scene `s` (a group without `bound`) compiled: it must derive a bound from the shape, and its scene
// evaluations at W×H evaluate at most `per_eval` shapes each on average (the hierarchy culls the rest).
Compiled derived_group(const std::string& s, const std::string& name, int W, int H, double per_eval = 4) {
    auto path = write_temp(name, s);
    Compiled c = compile_path(path, CompileOptions{});
    INFO(c.diagnostics);
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.result.code, Catch::Contains("derived from the shape"));
    Evaluations counts = count_evaluations(path, CompileOptions{}, W, H);
    INFO(counts.shapes / counts.evals << " shapes per scene evaluation");
    CHECK(counts.evals > W * H);
    CHECK(counts.shapes / counts.evals <= per_eval);
    return c;
}

// Pixels of scene `s` (compiled as `c`) that differ by more than 2/255 in a channel from the same scene with
// `bound = R` written before each instance's shape_params: a derived bound draws what a written one does.
int differ_from_bounded(const std::string& s, const Compiled& c, double R, const std::string& name, int W, int H) {
    std::string b = s;
    const std::string line = fmt::format("bound = {}\n", R);
    for (size_t at = 0; (at = b.find("shape_params", at)) != std::string::npos; at += line.size() + 12) b.insert(at, line);
    Compiled bounded = compile_path(write_temp(name, b), CompileOptions{});
    REQUIRE(bounded.result.exit_code == 0);
    render::RenderResult x = render_compiled(c.result, W, H), y = render_compiled(bounded.result, W, H);
    REQUIRE(x.ok);
    REQUIRE(y.ok);
    int differ = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i)
            for (int k = 0; k < 3; ++k)
                if (std::fabs(x.image.pixel(i, j)[k] - y.image.pixel(i, j)[k]) > 2.0 / 255) {
                    ++differ;
                    break;
                }
    return differ;
}

}  // namespace

TEST_CASE("1000 rings are one loop and one case of each dispatch on every target", "[instancing]") {
    auto path = write_temp("rings_1000.iq", rings_scene(1000, false));
    for (Target t : {Target::Shadertoy, Target::WebGL2, Target::GLSL330}) {
        CompileOptions o;
        o.target = t;
        o.verify_each = true;
        Compiled c = compile_path(path, o);
        INFO(target_name(t) << "\n" << c.diagnostics);
        REQUIRE(c.result.exit_code == 0);  // glslang accepted it
        const std::string& code = c.result.code;
        if (t == Target::Shadertoy) {
            // Constant parameters: a bound derived from the ring (ir/Support.h); the rings' spheres fill a lattice,
            // so the cells near the point are found by arithmetic: the nearest cell's member, then one loop over
            // the cells within reach, each calling the shape once.
            CHECK(count(code, "ring_lambert: 1000 instances on a 10×10×10 lattice: the cells within reach") == 1);
            CHECK(count(code, "ring(q") == 3);  // and once in iqc_distance_of (the normal's taps)
        } else {
            // Sliders: the ring's extent over its slider range (up to (2, 2): 4 units on a grid of 1) would make
            // spheres that overlap too much to skip anything; the bound is derived over the members' values (all
            // the same here), and the hierarchy it gives is guarded by iqc_prepare's test that the sliders are
            // there (every node entered where not). The shape is called once there (and in iqc_distance_of).
            CHECK(count(code, "ring_lambert: 1000 instances, a bounding-box hierarchy of") == 1);
            CHECK(count(code, "ring(q, ") == 2);
            CHECK_THAT(code, Catch::Contains("ring_lambert_within_hull <= 0.5"));
        }
        // One call of each part of the material (the light-independent part and the light's part) for the
        // rings and the ground, which share it: its k_d switched by the id (the calls pass).
        CHECK(count(code, "if (id >= 0 && id < 1001) {") == 2);
        CHECK(count(code, "c = lambert_ambient(") == 1);
        CHECK(count(code, "c = lambert_light(") == 1);
        CHECK(count(code, "if (id ==") < 5);
    }
    // Shadertoy: rings alike but for their place are evaluated as the first ring at the point moved by the
    // cell's offset (no integer division by the member's index in iqc_scene); the normal's taps keep the
    // grid's offsets as arithmetic on the index; a value every ring shares is one constant.
    Compiled st = compile_path(path);
    const std::string& sc = st.result.code;
    size_t from = sc.find("vec2 iqc_scene(vec3 p) {"), to = sc.find("\n}\n", from);
    REQUIRE(from != std::string::npos);
    const std::string scene_fn = sc.substr(from, to - from);
    CHECK_THAT(scene_fn, Catch::Contains(" * vec3(1.0, 0.5, 1.0))) + vec3(5.0, 0.7, 5.0);"));
    CHECK_THAT(scene_fn, !Catch::Contains("%"));
    // (id - 1) mod 10 by a multiplication and a shift: llvmpipe scalarises an integer division by 10.
    CHECK_THAT(sc, Catch::Contains("vec3 q = p + vec3(5.0 - float((id - 1) - ((((id - 1) * 205) >> 11) * 10))"));
    CHECK_THAT(sc, !Catch::Contains("% 10"));
    CHECK(count(st.result.code, "const vec2 ring_shape_t = vec2(0.3, 0.08);") == 1);
}

TEST_CASE("the shader for 1000 instances is at most 3 times the one for 10", "[instancing]") {
    for (bool irregular : {false, true})
        for (Target t : {Target::Shadertoy, Target::WebGL2, Target::GLSL330}) {
            CompileOptions o;
            o.target = t;
            Compiled small = compile_path(write_temp("rings_10.iq", rings_scene(10, irregular)), o);
            Compiled large = compile_path(write_temp("rings_1000.iq", rings_scene(1000, irregular)), o);
            REQUIRE(small.result.exit_code == 0);
            REQUIRE(large.result.exit_code == 0);
            INFO(target_name(t) << (irregular ? " irregular" : " grid") << ": " << small.result.code.size() << " and "
                                << large.result.code.size() << " bytes");
            // Irregular tables on Shadertoy are data in the code: compact, but they grow with the count.
            if (irregular && t == Target::Shadertoy) CHECK(large.result.code.size() < 40 * small.result.code.size());
            else CHECK(large.result.code.size() <= 3 * small.result.code.size());
        }
}

TEST_CASE("webgl2 puts per-instance data in uniform blocks, or past 16 KiB a data texture, described in --meta", "[instancing]") {
    CompileOptions o;
    o.target = Target::WebGL2;
    Compiled hundred = compile_path(write_temp("rings_100i.iq", rings_scene(100, true)), o);
    REQUIRE(hundred.result.exit_code == 0);
    CHECK_THAT(hundred.result.code, Catch::Contains("layout(std140) uniform iqc_block_0 {"));
    CHECK(hundred.result.inputs.texture.name.empty());
    auto meta = nlohmann::json::parse(hundred.result.meta);
    REQUIRE(meta["blocks"].size() >= 1);
    CHECK(meta["blocks"][0]["name"] == "iqc_block_0");
    // A thousand tilted rings: their matrices alone are 48 KB in std140, past one block: the texture.
    Compiled thousand = compile_path(write_temp("rings_1000i.iq", rings_scene(1000, true)), o);
    REQUIRE(thousand.result.exit_code == 0);
    CHECK_THAT(thousand.result.code, Catch::Contains("uniform highp sampler2D iqc_data;"));
    auto tm = nlohmann::json::parse(thousand.result.meta);
    CHECK(tm["texture"]["name"] == "iqc_data");
    CHECK(tm["texture"]["width"] == 1024);
    // Every ring's material parameter is a slider of its own, with its place in the texture.
    int rings = 0;
    for (const auto& p : tm["parameters"])
        if (p["module"] == "lambert" && p["name"] == "k_d" && p["instance"] != "ground_1") {
            ++rings;
            CHECK(p["storage"] == "texture");
            CHECK(p["offsets"].size() == 3);
        }
    CHECK(rings == 1000);
}

TEST_CASE("a group without bound that no hierarchy can cull on a slider target is a located warning", "[instancing]") {
    // Found by a new-user trial: on webgl2 the rings' derived sphere must hold over their sliders' ranges (t up
    // to (2, 2): 4 units wide on a grid of 1) and was refused, so every step evaluated all 100 rings, silently.
    // Now the sphere is derived over the members' values (a hierarchy guarded at run time: trial77), and only rings
    // too wide at their values as well (t = (1.8, 0.5) on a grid of 1) are evaluated every step: that is warned.
    CompileOptions o;
    o.target = Target::WebGL2;
    {
        Compiled web = compile_path(write_temp("rings_100_sliders.iq", rings_scene(100, false)), o);
        REQUIRE(web.result.exit_code == 0);
        CHECK_THAT(web.diagnostics, !Catch::Contains("without `bound`"));
        CHECK_THAT(web.result.code, Catch::Contains("ring_lambert_within_hull"));
    }
    std::string wide = rings_scene(100, false);
    wide.replace(wide.find("default = (0.3, 0.08)"), 21, "default = (1.8, 0.5)");
    auto path = write_temp("rings_100_sliders.iq", wide);
    Compiled web = compile_path(path, o);
    REQUIRE(web.result.exit_code == 0);
    CHECK_THAT(web.diagnostics, Catch::Contains("rings_100_sliders.iq:"));
    CHECK_THAT(web.diagnostics, Catch::Contains("warning: 100 instances of 'ring' without `bound` are all evaluated at every step on "
                                                "this target: the bounding sphere iqc derives from the shape over its sliders' "
                                                "ranges, and over its members' values alone, is unbounded or wider than their spacing"));
    // Shadertoy's constants: no warning (the rings at these values are marched in one loop there too, unwarned).
    Compiled toy = compile_path(path);
    REQUIRE(toy.result.exit_code == 0);
    CHECK_THAT(toy.diagnostics, !Catch::Contains("without `bound`"));
    // With `bound`, webgl2 has its hierarchy: no warning.
    Compiled bounded = compile_path(write_temp("rings_100_bound.iq", rings_scene(100, false, 0.4)), o);
    REQUIRE(bounded.result.exit_code == 0);
    CHECK_THAT(bounded.diagnostics, !Catch::Contains("without `bound`"));
}

TEST_CASE("Shadertoy --meta names each member's element of a group's constant table", "[instancing]") {
    // Found by a new-user trial: every member's k_d said "constant": "lambert_material_k_d", an array of 100 in the
    // shader, with no index; a tool could not tell which element was whose (webgl2's block members had theirs).
    std::string scene = "[[lights]]\nposition = [-5, 8, -6]\n";
    for (int i = 0; i < 100; ++i)
        scene += fmt::format("[[shapes]]\nname = \"s{}\"\ntype = \"sphere\"\nmaterial = \"lambert\"\ntransform = \"T(({}, 0, {}))\"\n"
                             "material_params = {{ k_d = [{:.2f}, 0.5, 0.5] }}\n",
                             i, i % 10 - 5, i / 10 - 5, 0.01 * i);
    Compiled c = compile_path(write_temp("members_100_meta.iq", scene));
    REQUIRE(c.result.exit_code == 0);
    auto meta = nlohmann::json::parse(c.result.meta);
    std::set<std::string> elements;
    std::string table;
    for (const auto& p : meta["parameters"])
        if (p["name"] == "k_d") {
            REQUIRE(p["storage"] == "constant");
            std::string at = p["constant"];
            size_t open = at.find('[');
            REQUIRE(open != std::string::npos);
            table = at.substr(0, open);
            elements.insert(at);
            CHECK(p["type"] == "vec3");
        }
    CHECK(elements.size() == 100);  // each its own element
    CHECK(elements.count(table + "[0]") == 1);
    CHECK(elements.count(table + "[99]") == 1);
    for (const auto& p : meta["parameters"])  // s37's element holds its colour
        if (p["name"] == "k_d" && p["instance"] == "s37") CHECK(p["default"][0] == Approx(0.37));
    CHECK_THAT(c.result.code, Catch::Contains("const vec3 " + table + "[100]"));
}

TEST_CASE("on Shadertoy a hierarchy's members take its leaf order: no table of that order, each instance's data in its own element",
          "[instancing][bvh]") {
    // 100 spheres scattered (no lattice), each with `bound` and its own colour: a bounding-volume hierarchy. The
    // members are numbered in its leaf order, so a leaf's members are a run of the per-member tables (a table of
    // the leaf order cost llvmpipe's compile a third of 1,000 rings' code tables, and a dependent lookup per
    // member). Each instance's parameters must still be its own: --meta names each element's instance.
    std::string scene = "[[lights]]\nposition = [-5, 8, -6]\n";
    uint32_t h = 777;
    auto rnd = [&] {
        h = h * 1664525u + 1013904223u;
        return double(h >> 8) / double(1u << 24);
    };
    std::map<std::string, double> red;
    for (int i = 0; i < 100; ++i) {
        double x = 12 * rnd() - 6, y = 2 * rnd(), z = 12 * rnd() - 6, r = 0.01 * ((i * 37) % 100);
        red[fmt::format("s{}", i)] = r;
        scene += fmt::format("[[shapes]]\nname = \"s{}\"\ntype = \"sphere\"\nmaterial = \"lambert\"\nbound = 1.1\n"
                             "transform = \"T(({:.3f}, {:.3f}, {:.3f}))\"\nmaterial_params = {{ k_d = [{:.2f}, 0.5, 0.5] }}\n",
                             i, x, y, z, r);
    }
    const auto path = write_temp("scattered_100.iq", scene);
    for (Target t : {Target::Shadertoy, Target::WebGL2}) {
        CompileOptions o;
        o.target = t;
        Compiled c = compile_path(path, o);
        INFO(target_name(t) << "\n" << c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        CHECK_THAT(c.result.code, Catch::Contains("100 instances, a bounding-box hierarchy of"));
        // Shadertoy: the leaf order, no table of it. webgl2 (sliders): the scene's order, kept by the html page's
        // saved slider values across `iqc serve`'s reloads, and a table of the leaf order.
        if (t == Target::Shadertoy) CHECK_THAT(c.result.code, !Catch::Contains("tree_members"));
        else CHECK_THAT(c.result.code, Catch::Contains("tree_members"));
        auto meta = nlohmann::json::parse(c.result.meta);
        int seen = 0;
        bool scene_order = true;
        for (const auto& p : meta["parameters"])
            if (p["name"] == "k_d" && red.count(p["instance"].get<std::string>())) {
                INFO(p.dump());
                CHECK(p["default"][0].get<double>() == Approx(red[p["instance"].get<std::string>()]));
                scene_order &= p["instance"] == fmt::format("s{}", seen);
                ++seen;
            }
        CHECK(seen == 100);
        CHECK(scene_order == (t != Target::Shadertoy));
        if (t == Target::Shadertoy) {
            // The table's element k holds the colour of the instance --meta names for element k.
            for (const auto& p : meta["parameters"])
                if (p["name"] == "k_d" && p["instance"] == "s37") {
                    std::string at = p["constant"];
                    const size_t open = at.find('['), close = at.find(']');
                    REQUIRE(close != std::string::npos);
                    const int k = std::stoi(at.substr(open + 1, close - open - 1));
                    const size_t table = c.result.code.find("const vec3 " + at.substr(0, open) + "[100] = vec3[100](");
                    REQUIRE(table != std::string::npos);
                    size_t e = c.result.code.find("vec3(", c.result.code.find('(', table) + 1);
                    for (int j = 0; j < k; ++j) e = c.result.code.find("vec3(", e + 1);
                    CHECK(std::stod(c.result.code.substr(e + 5)) == Approx(red["s37"]));
                }
        }
    }
}

TEST_CASE("100 and 1000 rings draw the reference's instances at the reference's depths on both targets", "[instancing][render]") {
    // Each storage path once (CI has two slow cores; the double-precision reference walks every instance
    // at every step): 100 jittered rings as Shadertoy tables and as webgl2 uniform blocks, 1000 rings as a
    // Shadertoy lattice and, jittered and tilted, as webgl2's data texture.
    const int W = 64, H = 36;
    struct Case { int n; bool irregular; Target t; };
    for (Case cs : {Case{100, true, Target::Shadertoy}, Case{100, true, Target::WebGL2}, Case{1000, false, Target::Shadertoy},
                    Case{1000, true, Target::WebGL2}}) {
        const int n = cs.n;
        const bool irregular = cs.irregular;
        const Target t = cs.t;
        CompileOptions o;
        o.target = t;
        o.ids = true;
        Compiled c = compile_path(write_temp(fmt::format("rings_{}_{}.iq", n, irregular), rings_scene(n, irregular)), o);
        INFO(n << " rings, " << (irregular ? "irregular, " : "grid, ") << target_name(t) << "\n" << c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        render::RenderResult r = render_compiled(c.result, W, H);
        INFO(r.error);
        REQUIRE(r.ok);
        Agreement a = against_reference(c.result, r, W, H, 4);
        // Silhouettes may differ between float and double by a sample or two; a wrong or black ring would not.
        CHECK(a.disagree <= a.samples / 50);
        CHECK(a.rings > (n == 100 ? a.samples / 100 : a.samples / 8));  // the rings are visible
    }
}

TEST_CASE("a lattice of 1000 tori draws the reference with or without bound", "[instancing][render]") {
    // Found by a new-user trial: rays that needed more than 65 steps through 1,000 instances passed llvmpipe's
    // limit of 65,535 loop iterations per pixel and drew other pixels' tori (and `bound`, which changes the
    // step counts, changed the picture). The emitter now unrolls long loops.
    auto lattice = [](bool bound) {
        std::string s = "[camera]\nposition = [0, 12, -30]\ntarget = [0, 0, 0]\n";
        for (int i = 0; i < 1000; ++i)
            s += fmt::format("[[shapes]]\ntype = \"torus\"\ntransform = \"T(({}, {}, {}))⋅`R_x`(0.5)⋅S((0.5, 0.5, 0.5))\"\n{}",
                             2 * (i / 100) - 10, 2 * ((i / 10) % 10) - 10, 2 * (i % 10) - 10, bound ? "bound = 1.2\n" : "");
        return s;
    };
    const int W = 48, H = 27;
    std::vector<int> ids[2];
    for (int b = 0; b < 2; ++b) {
        Compiled c = compile_ids(fmt::format("lattice_{}.iq", b), lattice(b == 1));
        REQUIRE(c.result.exit_code == 0);
        render::RenderResult r = render_compiled(c.result, W, H);
        INFO(r.error);
        REQUIRE(r.ok);
        const SceneModel& model = *c.result.model;
        int disagree = 0, hits = 0, samples = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                int gid = int(std::lround(r.image.pixel(x, y)[1]));
                ids[b].push_back(gid);
                hits += gid >= 0;
                if ((x + y) % 3 != 0) continue;  // the reference at a third of the pixels (1000 instances per step)
                ++samples;
                std::array<double, 3> ro, rd;
                model.ray(x, y, W, H, ro, rd);
                int id = -1;
                model.trace(ro, rd, &id);
                if (gid != id) {
                    ++disagree;
                    UNSCOPED_INFO(fmt::format("pixel ({}, {}): shader id {}, reference id {}", x, y, gid, id));
                }
            }
        INFO((b ? "with" : "without") << " bound: " << disagree << " of " << samples << " samples disagree, " << hits << " hits");
        CHECK(hits > W * H / 10);
        CHECK(disagree <= samples / 100);  // grazing silhouettes within the hit tolerance, not whole tori
    }
    int changed = 0;
    for (size_t i = 0; i < ids[0].size(); ++i) changed += ids[0][i] != ids[1][i];
    INFO(changed << " pixels change with bound");
    CHECK(changed <= W * H / 200);
}

TEST_CASE("rings with bound: a lattice on a grid, a bounding-volume hierarchy otherwise: few shapes per scene evaluation, the "
          "reference's picture",
          "[instancing][render][lattice]") {
    // 1,000 rings each with `bound`: on a grid, the members whose cells are within reach of the point (arithmetic on
    // the cell, no tables); jittered and tilted, the hierarchy's nodes whose boxes are nearer than the nearest
    // distance found so far (without either every step tested all 1,000 spheres: a frame 8.5 times that of 10
    // rings on llvmpipe). 700 rings fill 8 layers of 9 × 9 and 52 cells of a 9th: a lattice with empty cells
    // (here in WebGL2 GLSL: the lattice needs no tables on any target).
    const int W = 64, H = 36;
    for (int variant : {0, 1, 2}) {
        const bool irregular = variant == 1;
        const int n = variant == 2 ? 700 : 1000;
        CompileOptions o;
        o.target = irregular || variant == 2 ? Target::WebGL2 : Target::Shadertoy;
        o.ids = true;
        auto path = write_temp(fmt::format("rings_bound_{}.iq", variant), rings_scene(n, irregular, 0.4));
        Compiled c = compile_path(path, o);
        INFO((irregular ? "irregular, webgl2" : variant == 2 ? "partial grid, webgl2" : "grid, shadertoy") << "\n" << c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        if (irregular) {
            CHECK_THAT(c.result.code, Catch::Contains("ring_lambert: 1000 instances, a bounding-box hierarchy of 3 levels"));
            // One member loop at the hierarchy's last level, and iqc_distance_of (the normal's taps).
            CHECK(count(c.result.code, "ring(q, ") == 2);
        } else {
            CHECK_THAT(c.result.code, Catch::Contains(variant == 2 ? "ring_lambert: 700 instances on a 9×9×9 lattice: the cells within reach"
                                                                   : "ring_lambert: 1000 instances on a 10×10×10 lattice: the cells within reach"));
            CHECK_THAT(c.result.code, !Catch::Contains("bounding-box hierarchy"));
            // The nearest cell's member, the cells' loop, and iqc_distance_of.
            CHECK(count(c.result.code, variant == 2 ? "= ring(" : "ring(q") == 3);
            // Shadertoy: the rings are alike but for their place: the first ring at the point moved by the cell's
            // offset. webgl2: each ring has its own slider values, read by its index, at the point moved to its
            // cell's centre (arithmetic on the cell, no offset table, no integer division). Empty cells are skipped.
            CHECK_THAT(c.result.code, Catch::Contains(variant == 2 ? "(p - vec3(-4.5, -0.7, -4.5)) - (" : ") + vec3(5.0, 0.7, 5.0);"));
            if (variant == 2) {
                CHECK_THAT(c.result.code, Catch::Contains(">= 700"));
                const size_t from = c.result.code.find("vec2 iqc_scene(");
                REQUIRE(from != std::string::npos);
                const std::string scene_fn = c.result.code.substr(from, c.result.code.find("\n}\n", from) - from);
                CHECK_THAT(scene_fn, !Catch::Contains("% 9"));
                CHECK_THAT(scene_fn, !Catch::Contains("offset["));
            }
        }
        render::RenderResult r = render_compiled(c.result, W, H);
        INFO(r.error);
        REQUIRE(r.ok);
        Agreement a = against_reference(c.result, r, W, H, 3);
        CHECK(a.disagree <= a.samples / 50);
        CHECK(a.rings > a.samples / 8);
        // Instrumented: shapes evaluated per scene evaluation (the stats `iqc render --stats` prints).
        Evaluations counts = count_evaluations(path, o, W, H);
        INFO(counts.shapes / counts.evals << " shapes per scene evaluation");
        CHECK(counts.evals > W * H);
        CHECK(counts.shapes / counts.evals <= 16);
    }
}

TEST_CASE("rings without bound get one derived from the shape: a lattice, few shapes per evaluation, the reference's picture",
          "[instancing][render][bvh]") {
    // A group of 48 or more instances without `bound` gets the radius interval arithmetic proves contains the
    // shape (ir/Support.h): the ring's (0.3, 0.08) is within 0.38 of its origin; the derived radius is a
    // little more. Without it every step evaluated all 1,000 rings.
    const int W = 64, H = 36;
    CompileOptions o;
    o.ids = true;
    auto path = write_temp("rings_derived.iq", rings_scene(1000, false, 0));
    Compiled c = compile_path(path, o);
    INFO(c.diagnostics);
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.result.code, Catch::Contains("ring_lambert: 1000 instances on a 10×10×10 lattice"));
    CHECK_THAT(c.result.code, Catch::Contains(", derived from the shape)"));
    // The ring is cheap (two lengths): its derived sphere bounds the lattice's reach but does not stand in for
    // it per member (that cost 100 instances' frame 5%), so the radius is read from the loop's comment.
    std::string code = c.result.code;
    const std::string within = "each member within ";
    size_t at = code.find(within);
    REQUIRE(at != std::string::npos);
    double R = std::stod(code.substr(at + within.size()));
    CHECK(R >= 0.38);
    CHECK(R <= 0.38 * 1.15);
    render::RenderResult r = render_compiled(c.result, W, H);
    INFO(r.error);
    REQUIRE(r.ok);
    Agreement a = against_reference(c.result, r, W, H, 3);
    CHECK(a.disagree <= a.samples / 50);
    CHECK(a.rings > a.samples / 8);
    Evaluations counts = count_evaluations(path, CompileOptions{}, W, H);
    INFO(counts.shapes / counts.evals << " shapes per scene evaluation");
    CHECK(counts.shapes / counts.evals <= 16);
    // A group below 48 members keeps its plain loop, and a plane has no extent to derive: no bound.
    Compiled small = compile_path(write_temp("rings_small.iq", rings_scene(40, false, 0)), CompileOptions{});
    REQUIRE(small.result.exit_code == 0);
    CHECK_THAT(small.result.code, !Catch::Contains("derived from the shape"));
}

TEST_CASE("a piecewise shape without bound gets one by case splitting: 100 octahedra, few shapes per evaluation",
          "[instancing][render][bvh]") {
    // The standard library's octahedron picks one of three permutations of |p| (a piecewise choice): one pass of
    // intervals takes their hull and proves no box free, so it got no derived bound (and no scene box), and every
    // step evaluated all 100 (98 shape evaluations per scene evaluation at 320×180). Case splitting
    // (ir/CaseSplit.h) proves it within a little more than its size, 0.35.
    const int W = 64, H = 36;
    std::string s = "[camera]\nposition = [0, 0, -14]\ntarget = [0, 0, 0]\n";
    for (int k = 0; k < 100; ++k)
        s += fmt::format("[[shapes]]\ntype = \"octahedron\"\nshape_params = {{ s = 0.35 }}\ntransform = \"T(({}, {}, 0))⋅`R_x`({})\"\n",
                         k % 10 - 4.5, k / 10 - 4.5, 0.4 * (k % 7));
    Compiled c = derived_group(s, "octahedra_derived.iq", W, H);
    // The picture: the same as with a `bound` written (0.36, just over the octahedron's 0.35).
    CHECK(differ_from_bounded(s, c, 0.36, "octahedra_bounded.iq", W, H) <= W * H / 100);
}

TEST_CASE("a polytope shape without bound gets one from its planes: 100 tetrahedra, few shapes per evaluation",
          "[instancing][render][bvh][convex-bound]") {
    // The standard library's tetrahedron is the largest of its four face planes' distances: over a half-space
    // beyond any plane each is unbounded below, so interval arithmetic closed only the y sides of its box and
    // derived no bound, and every step evaluated all 100 (95 shape evaluations per scene evaluation at 320×180).
    // Its planes' Farkas combinations (ir/ConvexBound.h) give the exact box and circumradius (3 × 0.25).
    const int W = 64, H = 36;
    std::string s = "[camera]\nposition = [0, 6, -14]\ntarget = [0, 0, 0]\n";
    for (int k = 0; k < 100; ++k)
        s += fmt::format("[[shapes]]\ntype = \"tetrahedron\"\nshape_params = {{ r = 0.25 }}\ntransform = \"T(({}, 0, {}))\"\n",
                         k % 10 - 4.5, k / 10 - 4.5);
    Compiled c = derived_group(s, "tetrahedra_derived.iq", W, H);
    CHECK_THAT(c.result.code, !Catch::Contains("1.0e+30"));  // the scene's box is closed on every side
    // The picture: the same as with a `bound` written (0.76, just over the circumradius 0.75).
    CHECK(differ_from_bounded(s, c, 0.76, "tetrahedra_bounded.iq", W, H) <= W * H / 100);
}

TEST_CASE("a shape turned inside its module by a constant rotation gets a bound: 100 turned boxes", "[instancing][bvh][box]") {
    // q = R p inside the module mixes every axis, so intervals proved no side of its box: no scene box, no
    // derived bound (93 shape evaluations per scene evaluation at 320×180). Analysed over boxes of q and mapped
    // back through R⁻¹ (ir/Support.cpp, mapped_box): both.
    const int W = 64, H = 36;
    std::string s =
        "[modules]\nturned = \"\"\"\nshape\nq = |[0.8775825618903728 0 0.479425538604203; 0.2298488470659301 "
        "0.8775825618903728 -0.4207354924039483; -0.4207354924039483 0.479425538604203 0.7701511529340699] p| - (1, 0.5, "
        "0.25)\nD = ‖max(q, 0)‖ + min(max(q_1, q_2, q_3), 0)\nwhere\np ∈ ℝ³\n\"\"\"\n"
        "[camera]\nposition = [0, 6, -16]\ntarget = [0, 0, 0]\n";
    for (int k = 0; k < 100; ++k)
        s += fmt::format("[[shapes]]\ntype = \"turned\"\ntransform = \"T(({}, 0, {}))\"\n", (k % 10 - 4.5) * 2.5, (k / 10 - 4.5) * 2.5);
    Compiled c = derived_group(s, "turned_boxes.iq", W, H);
    CHECK_THAT(c.result.code, !Catch::Contains("1.0e+30"));  // the scene's box is closed on every side
}

TEST_CASE("a union of a turned part and a ball gets a bound from its box: 100 of them", "[instancing][bvh][box]") {
    // Interval arithmetic finds no radius for min(box(M p), ball), nor the rotated analysis of the whole (the
    // ball's coordinates are unbounded there): 97 shape evaluations per scene evaluation at 320×180. The box
    // support_box finds operand by operand gives one (its farthest corner).
    const int W = 64, H = 36;
    std::string s =
        "[modules]\nmixed = \"\"\"\nshape\nbox(x, b) = ‖max(|x| - b, 0)‖ + min(max((|x| - b)_1, (|x| - b)_2, (|x| - b)_3), 0) "
        "where x ∈ ℝ³, b ∈ ℝ³\nD = min(box([0.7648421872844885 0.2508701838500143 0.5933637833613874; 0 0.9210609940028851 "
        "-0.3894183423086505; -0.644217687237691 0.2978435767000479 0.7044663052755917] p, (1, 0.2, 0.3)), ‖p - (2, 0, 0)‖ - "
        "0.5)\nwhere\np ∈ ℝ³\n\"\"\"\n[camera]\nposition = [0, 8, -30]\ntarget = [0, 0, 0]\n";
    for (int k = 0; k < 100; ++k)
        s += fmt::format("[[shapes]]\ntype = \"mixed\"\ntransform = \"T(({}, 0, {}))\"\n", (k % 10 - 4.5) * 6, (k / 10 - 4.5) * 6);
    Compiled c = derived_group(s, "mixed_parts.iq", W, H);
    CHECK_THAT(c.result.code, !Catch::Contains("1.0e+30"));
}

TEST_CASE("the hierarchy serves the unbounded scene only for exact shapes", "[instancing]") {
    // Soft shadows read iqc_scene_unbounded's value: skipping a subtree leaves it as is only where every
    // distance is at least its sphere's (an exact distance); other shapes are all evaluated there.
    for (bool exact : {false, true}) {
        std::string s = rings_scene(100, false, 0.4);
        s.replace(s.find("ring = \"\"\"\nshape\n"), 17, exact ? "ring = \"\"\"\nshape\n# exact\n" : "ring = \"\"\"\nshape\n");
        s.replace(s.find("[[lights]]"), 10, "[effects]\nshadows = \"soft\"\n[[lights]]");
        Compiled c = compile_path(write_temp(fmt::format("rings_soft_{}.iq", exact), s));
        INFO(c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        // iqc_scene: the lattice; iqc_scene_unbounded: the hierarchy for an exact shape.
        CHECK(count(c.result.code, "100 instances on a 4×7×4 lattice") == 1);
        CHECK(count(c.result.code, "a bounding-box hierarchy of") == (exact ? 1 : 0));
        CHECK(count(c.result.code, "{  // ring_lambert: 100 instances (unrolled by 2)") == (exact ? 0 : 1));  // every member
    }
}

TEST_CASE("small groups with bound compile on every target: lattices, repeats, coincident members", "[instancing]") {
    // Found by a new-user trial: 16 to 40 rings on a grid with `bound` stopped with an internal error (the
    // tables pass turned the hierarchy's ℤ tables into real arithmetic and indexed a table with it), as did
    // spheres at (i, 0, i mod 3), (i, 0, i² mod 5) and coincident pairs, at 16 members and at 100. (Groups
    // of fewer than 48 have no hierarchy since: a loop is faster there.)
    std::vector<std::pair<std::string, std::string>> scenes;
    for (int n : {48, 49, 56, 64, 80}) scenes.push_back({fmt::format("rings_{}", n), rings_scene(n, false, 0.4)});
    for (int pattern = 0; pattern < 3; ++pattern) {
        std::string s = "[camera]\nposition = [8, 3, -8]\ntarget = [8, 0, 0]\n";
        for (int i = 0; i < 100; ++i) {
            int z = pattern == 0 ? i % 3 : pattern == 1 ? (i * i) % 5 : 0;
            int x = pattern == 2 ? i % 8 : i;
            s += fmt::format("[[shapes]]\ntype = \"sphere\"\ntransform = \"T(({}, 0, {}))\"\nbound = 1.2\n", x, z);
        }
        scenes.push_back({fmt::format("spheres_{}", pattern), s});
    }
    for (const auto& [name, text] : scenes)
        for (Target t : {Target::Shadertoy, Target::WebGL2, Target::GLSL330}) {
            CompileOptions o;
            o.target = t;
            Compiled c = compile_path(write_temp(name + ".iq", text), o);
            INFO(name << " " << target_name(t) << "\n" << c.diagnostics << c.result.internal);
            CHECK(c.result.exit_code == 0);
            // Rings fill a lattice (the last layer in part); the spheres' layouts are none.
            CHECK_THAT(c.result.code, Catch::Contains(name.rfind("rings", 0) == 0 ? " lattice: the cells within reach" : "a bounding-box hierarchy of"));
        }
}

TEST_CASE("a hierarchy node standing in for its members is never a hit", "[instancing][render]") {
    // Found by a new-user trial: a node far from the ray stands in with its box's distance and carried the
    // id of the group's first member; at the step cap the ray's last sample within the pixel's cone counted
    // as a hit, so member 0 — behind the camera — was drawn in the background (74 pixels at 160×90). Now a
    // stand-in has id -1, and the step cap takes no sample without an instance.
    std::string s = "[camera]\nposition = [0, 1.5, -5]\ntarget = [0, 1, 50]\n[render]\nmax_steps = 24\nmax_dist = 120\n";
    uint32_t h = 7;
    auto rnd = [&] {
        h = h * 1664525u + 1013904223u;
        return double(h >> 8) / double(1u << 24);
    };
    for (int i = 0; i < 300; ++i) {
        double x = -30 + 60 * rnd(), y = -0.6 + 3.6 * rnd(), z = 10 + 80 * rnd();
        if (i == 0) x = 0, y = 0, z = -50;  // behind the camera
        s += fmt::format("[[shapes]]\ntype = \"torus\"\ntransform = \"T(({:.3f}, {:.3f}, {:.3f}))⋅`R_x`({:.2f})\"\nbound = 1.21\n", x, y, z,
                         0.37 * i);
    }
    Compiled c = compile_ids("behind.iq", s);
    REQUIRE(c.result.exit_code == 0);
    REQUIRE_THAT(c.result.code, Catch::Contains("a bounding-box hierarchy of"));
    render::RenderResult r = render_compiled(c.result, 160, 90);
    REQUIRE(r.ok);
    int behind = 0, hits = 0;
    for (int y = 0; y < 90; ++y)
        for (int x = 0; x < 160; ++x) {
            int id = int(std::lround(r.image.pixel(x, y)[1]));
            behind += id == 0;
            hits += id >= 0;
        }
    INFO(hits << " hits");
    CHECK(hits > 100);
    CHECK(behind == 0);
}

TEST_CASE("a Shadertoy table past 4,096 vec4 slots is told of, located: llvmpipe compiles it for minutes", "[instancing]") {
    // A trial's tori, each tilted by its own angle (after a turn about y shared by all: every entry of their maps
    // differs): mat3[N] takes 3N slots. At 1,380 (4,140 slots) llvmpipe's compile ran past a minute (1,300: 7.9
    // s); webgl2 keeps the table in a uniform block.
    auto tilted = [](int n, bool one_axis = false) {
        std::string s = "[camera]\nposition = [0, 8, -20]\ntarget = [0, 0, 0]\n";
        for (int i = 0; i < n; ++i)
            s += fmt::format("[[shapes]]\ntype = \"torus\"\ntransform = \"T(({}, 0, {})){}⋅`R_x`({:.4f})\"\n", i % 40 - 20, i / 40 - 17,
                             one_axis ? "" : "⋅`R_y`(0.3)", 0.001 * i);
        return s;
    };
    Compiled big = compile_path(write_temp("tilted_1380.iq", tilted(1380)));
    REQUIRE(big.result.exit_code == 0);
    CHECK_THAT(big.diagnostics, Catch::Contains("tilted_1380.iq:5:8: warning: on Shadertoy the table 'torus_to_object' (1380 elements, "
                                                "4140 vec4 slots) is code"));
    CHECK(count(big.diagnostics, "warning: on Shadertoy the table") == 1);  // once per group
    CompileOptions o;
    o.target = Target::WebGL2;
    CHECK(compile_path(write_temp("tilted_1380.iq", tilted(1380)), o).diagnostics.find("vec4 slots") == std::string::npos);
    CHECK(compile_path(write_temp("tilted_1300.iq", tilted(1300))).diagnostics.find("vec4 slots") == std::string::npos);
    // Tilted about x alone, the maps differ in four entries, two values up to sign: one vec2 table (cos, sin),
    // read once a member, no mat3 table (llvmpipe compiles 1,380 of them in 1.4 s).
    Compiled split = compile_path(write_temp("tilted_x_1380.iq", tilted(1380, true)));
    REQUIRE(split.result.exit_code == 0);
    CHECK(split.diagnostics.find("vec4 slots") == std::string::npos);
    CHECK_THAT(split.result.code, Catch::Contains("const vec2 torus_to_object[1380] = vec2[1380](vec2(1,0),vec2(."));
    CHECK_THAT(split.result.code, Catch::Contains("per instance (.x: (2, 2), (3, 3); .y: (2, 3), −(3, 2); the others are constants)"));
    CHECK_THAT(split.result.code, !Catch::Contains("const float torus_to_object"));
    CHECK_THAT(split.result.code, !Catch::Contains("mat3 torus_to_object"));
}

TEST_CASE("a bounded group too large for a hierarchy on Shadertoy is told so, located", "[instancing][bvh]") {
    // Past 2,048 members the hierarchy's tables would be code (llvmpipe compiles them for minutes): the group is
    // one loop there, and said to be (it was silent; stop 20's trial).
    auto path = write_temp("rings_2049.iq", rings_scene(2049, true, 0.4));
    Compiled toy = compile_path(path);
    REQUIRE(toy.result.exit_code == 0);
    CHECK_THAT(toy.diagnostics, Catch::Contains("rings_2049.iq:39:8: warning: 2049 instances of 'ring' with `bound` are marched in "
                                                "one loop, without a bounding-volume hierarchy"));
    CHECK_THAT(toy.diagnostics, Catch::Contains("--target webgl2 keeps them in a texture"));
    CompileOptions o;
    o.target = Target::WebGL2;
    Compiled web = compile_path(path, o);
    REQUIRE(web.result.exit_code == 0);
    CHECK(web.diagnostics.find("bounding-volume hierarchy") == std::string::npos);
    Compiled small = compile_path(write_temp("rings_2048.iq", rings_scene(2048, true, 0.4)));
    CHECK(small.diagnostics.find("bounding-volume hierarchy") == std::string::npos);
    // On a grid the group needs no tables at any size: a lattice, no warning.
    Compiled grid = compile_path(write_temp("rings_grid_2049.iq", rings_scene(2049, false, 0.4)));
    REQUIRE(grid.result.exit_code == 0);
    CHECK(grid.diagnostics.find("bounding-volume hierarchy") == std::string::npos);
    CHECK_THAT(grid.result.code, Catch::Contains("2049 instances on a 15×10×15 lattice"));
    // Without `bound` too: past 2,048 members Shadertoy derives one from the shape where the centres form a
    // lattice (it needs no tables), and none where they do not (the flat loop).
    Compiled derived = compile_path(write_temp("rings_grid_2049_derived.iq", rings_scene(2049, false, 0)));
    REQUIRE(derived.result.exit_code == 0);
    CHECK_THAT(derived.result.code, Catch::Contains(", derived from the shape)"));
    CHECK_THAT(derived.result.code, Catch::Contains("2049 instances on a 15×10×15 lattice"));
    Compiled jittered = compile_path(write_temp("rings_irregular_2049_derived.iq", rings_scene(2049, true, 0)));
    REQUIRE(jittered.result.exit_code == 0);
    CHECK_THAT(jittered.result.code, !Catch::Contains("derived from the shape"));
    CHECK_THAT(jittered.result.code, !Catch::Contains("lattice"));
}

TEST_CASE("a lattice of members that differ (tilts, sizes) reads each member's data: the reference's picture", "[instancing][render][lattice]") {
    // Rings on a grid, each tilted by its own angle, or each with its own radii: the centres are a lattice, but
    // member k at p is not member 0 at a moved point, so the scene reads member k's transform and parameters.
    const int W = 64, H = 36;
    // Variant 2: positions written to 4 decimals on a spacing of 2/3 (a trial's thirds fell back to the
    // hierarchy): a lattice within 10⁻³ of the spacing, each member read at its own place.
    for (int variant : {0, 1, 2}) {
        std::string s = rings_scene(0, false, 0);
        for (int i = 0; i < 400; ++i) {
            double x = (i % 7) - 3.5, z = (i / 7) % 7 - 3.5, y = (i / 49) * 0.5 - 0.7;
            if (i >= 343) break;
            if (variant == 2) {
                s += fmt::format("[[shapes]]\ntype = \"ring\"\nmaterial = \"lambert\"\ntransform = \"T(({:.4f}, {}, {:.4f}))\"\nbound = 0.4\n",
                                 x * 2 / 3, y, z * 2 / 3);
                continue;
            }
            s += variant == 0 ? fmt::format("[[shapes]]\ntype = \"ring\"\nmaterial = \"lambert\"\ntransform = \"T(({}, {}, {}))⋅`R_x`({:.2f})\"\n"
                                            "bound = 0.4\n", x, y, z, 0.4 * (i % 5))
                              : fmt::format("[[shapes]]\ntype = \"ring\"\nmaterial = \"lambert\"\ntransform = \"T(({}, {}, {}))\"\n"
                                            "shape_params = {{ t = [{:.2f}, 0.08] }}\nbound = 0.4\n", x, y, z, 0.2 + 0.03 * (i % 4));
        }
        Compiled c = compile_ids(fmt::format("lattice_differ_{}.iq", variant), s);
        INFO(variant << "\n" << c.diagnostics);
        REQUIRE(c.result.exit_code == 0);
        CHECK_THAT(c.result.code, Catch::Contains("343 instances on a 7×7×7 lattice: the cells within reach"));
        if (variant == 1) CHECK_THAT(c.result.code, Catch::Contains("[nearest]"));  // member k's own data, by its index
        else if (variant == 2) CHECK_THAT(c.result.code, Catch::Contains("ring_lambert_offset[nearest]"));  // its own offset, not the cell's
        if (variant == 0) {
            // Tilted about x: the maps differ in four entries, two values up to sign (one vec2 table, not a mat3
            // table), and the rings sit on their cells' centres: the point is moved there by arithmetic on the cell,
            // no offset table in the scene function. The tilts repeat every 5 members: the table keeps one period,
            // read at k mod 5 (a multiplication and a shift).
            CHECK_THAT(c.result.code, Catch::Contains("const vec2 ring_lambert_to_object[5] = vec2[5]("));
            CHECK_THAT(c.result.code, Catch::Contains("ring_lambert_to_object[nearest - (((nearest * 205) >> 10) * 5)]"));
            CHECK_THAT(c.result.code, !Catch::Contains("mat3 ring_lambert_to_object"));
            const size_t from = c.result.code.find("vec2 iqc_scene(");
            REQUIRE(from != std::string::npos);
            CHECK_THAT(c.result.code.substr(from, c.result.code.find("\n}\n", from) - from), !Catch::Contains("offset["));
        }
        render::RenderResult r = render_compiled(c.result, W, H);
        INFO(r.error);
        REQUIRE(r.ok);
        Agreement a = against_reference(c.result, r, W, H, 3);
        CHECK(a.disagree <= a.samples / 50);
        CHECK(a.rings > a.samples / 20);
    }
}

TEST_CASE("a lattice member's own distance (the normal's taps) is computed at its cell's centre, the cell from the id", "[instancing][lattice]") {
    // 10 × 10 tori in a plane, each tilted about x by its own angle (bench/instances_100.iq): their offsets are
    // no arithmetic on the index, so iqc_distance_of evaluates member k at p minus its cell's centre, the cell
    // from k by integer division (no vec3[100] of offsets), and gives each member's own distance: the torus's
    // in that member's frame, evaluated here in double precision for every member at points around it.
    std::string s = rings_scene(0, false, 0);
    for (int k = 0; k < 100; ++k)
        s += fmt::format("[[shapes]]\ntype = \"ring\"\nmaterial = \"lambert\"\ntransform = \"T(({}, {}, 0))⋅`R_x`({:.1f})\"\nbound = 0.4\n",
                         (k % 10) - 4.5, (k / 10) - 4.5, 0.4 * (k % 7));
    Compiled c = compile_path(write_temp("lattice_tilts.iq", s));
    INFO(c.diagnostics);
    REQUIRE(c.result.exit_code == 0);
    const std::string& code = c.result.code;
    CHECK_THAT(code, Catch::Contains("100 instances on a 10×10×1 lattice"));
    CHECK_THAT(code, !Catch::Contains("offset"));  // no offset table, in iqc_scene or iqc_distance_of
    const size_t from = code.find("float iqc_distance_of(");
    REQUIRE(from != std::string::npos);
    const std::string dist = code.substr(from, code.find("\n}\n", from) - from);
    // k mod 10 and k div 10 by a multiplication and a shift (llvmpipe scalarises an integer division by 10).
    CHECK_THAT(dist, Catch::Contains(" * 103) >> 10"));
    CHECK_THAT(dist, !Catch::Contains("% 10") && !Catch::Contains("/ 10"));
    const ir::Module& m = c.result.model->ir;
    int fn = m.find(ir::names::kDistanceOf);
    REQUIRE(fn >= 0);
    double worst = 0;
    for (int k = 0; k < 100; ++k) {
        const double cx = (k % 10) - 4.5, cy = (k / 10) - 4.5, a = 0.4 * (k % 7);
        for (int j = 0; j < 8; ++j) {
            const double p[3] = {cx + 0.37 * std::cos(j), cy + 0.29 * std::sin(1.7 * j), 0.21 * std::cos(2.3 * j)};
            // The object point: R_x(a)⁻¹ (p − centre), the torus (0.3, 0.08) about its y axis.
            const double x = p[0] - cx, y = p[1] - cy, z = p[2];
            const double qy = std::cos(a) * y + std::sin(a) * z, qz = -std::sin(a) * y + std::cos(a) * z;
            const double want = std::hypot(std::hypot(x, qz) - 0.3, qy) - 0.08;
            ir::Value got = ir::evaluate(m, fn, {ir::Value{Type::vector(3), {p[0], p[1], p[2]}}, ir::Value{Type::integer(), {double(k + 1)}}});
            REQUIRE(got.v.size() >= 1);
            worst = std::max(worst, std::fabs(got.v[0] - want));
        }
    }
    CHECK(worst < 1e-9);
}

TEST_CASE("a lattice that fills the scene's box has no stand-in for far points unless effects read the scene there", "[instancing][render][lattice]") {
    // bench/instances_100.iq: 100 tori on a 10×10 lattice and nothing else. Every march is clipped to the scene's
    // box, which lies within a quarter spacing of the lattice's: the stand-in for points farther than that (the
    // lattice's box distance, id -1) would never serve, and is left out. Ambient occlusion (or soft shadows)
    // reads the scene anywhere, and a far sphere widens the box: the stand-in stays.
    const std::string text = read_text(std::filesystem::path(IQC_SOURCE_DIR) / "bench" / "instances_100.iq");
    const std::string stand_in = "distance to the box of the lattice's bounding spheres";
    Compiled c = compile_ids("lattice_alone.iq", text);
    INFO(c.diagnostics);
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.result.code, Catch::Contains("100 instances on a 10×10×1 lattice"));
    CHECK_THAT(c.result.code, !Catch::Contains(stand_in));
    render::RenderResult r = render_compiled(c.result, 64, 36);
    INFO(r.error);
    REQUIRE(r.ok);
    Agreement a = against_reference(c.result, r, 64, 36, 2);
    CHECK(a.disagree <= a.samples / 50);
    CHECK(a.rings > a.samples / 20);
    Compiled ao = compile_text("lattice_ao.iq", text + "\n[effects]\nao = true\n");
    REQUIRE(ao.result.exit_code == 0);
    CHECK_THAT(ao.result.code, Catch::Contains(stand_in));
    std::string far = text;
    far.replace(far.find("[modules]\n"), 10, "[modules]\nball = \"\"\"\nshape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n\"\"\"\n");
    Compiled wide = compile_text("lattice_wide.iq", far + "\n[[shapes]]\ntype = \"ball\"\ntransform = \"T((0, 0, 30))\"\n");
    INFO(wide.diagnostics);
    REQUIRE(wide.result.exit_code == 0);
    CHECK_THAT(wide.result.code, Catch::Contains(stand_in));
}

TEST_CASE("a lattice in a plane loops over its two axes only: the reference's picture", "[instancing][render][lattice]") {
    // Rings on a 7×1×7 grid (a floor of them: y has one cell): a loop over y of 0 or 1 trips around the other two
    // made 100 instances' frame 13% slower. An axis of one cell is no loop and no test: its one cell holds the
    // nearest member, so it is always in reach (the outer loop's bound is the other axis's span alone).
    const int W = 64, H = 36;
    auto loops_in_scene = [](const std::string& code) {
        const size_t from = code.find("vec2 iqc_scene(");
        const std::string body = code.substr(from, code.find("\n}\n", from) - from);
        int n = 0;
        for (size_t at = body.find("for (int "); at != std::string::npos; at = body.find("for (int ", at + 1)) ++n;
        return n;
    };
    std::string s = rings_scene(0, false, 0);
    s.replace(s.find("position = [0, 7, -13]"), 22, "position = [0, 3, -5.5]");  // nearer: the floor of rings fills the view
    for (int i = 0; i < 49; ++i)
        s += fmt::format("[[shapes]]\ntype = \"ring\"\nmaterial = \"lambert\"\ntransform = \"T(({}, 0.3, {}))⋅`R_x`({:.2f})\"\nbound = 0.4\n",
                         (i % 7) - 3.5, (i / 7) - 3.5, 0.3 * (i % 3));
    Compiled c = compile_ids("lattice_plane.iq", s);
    INFO(c.diagnostics);
    REQUIRE(c.result.exit_code == 0);
    CHECK_THAT(c.result.code, Catch::Contains("49 instances on a 7×1×7 lattice: the cells within reach"));
    CHECK(loops_in_scene(c.result.code) == 2);
    const size_t outer = c.result.code.find("for (int k = 0; k <= ");
    REQUIRE(outer != std::string::npos);
    const std::string header = c.result.code.substr(outer, c.result.code.find('{', outer) - outer);
    INFO(header);
    CHECK_THAT(header, !Catch::Contains("?"));  // no select of -1 where the one-cell axis were out of reach
    render::RenderResult r = render_compiled(c.result, W, H);
    INFO(r.error);
    REQUIRE(r.ok);
    Agreement a = against_reference(c.result, r, W, H, 3);
    INFO(a.rings << " of " << a.samples << " samples show a ring, " << a.disagree << " disagree");
    CHECK(a.disagree <= a.samples / 50);
    CHECK(a.rings > a.samples / 20);
    // A lattice of three axes keeps three loops.
    Compiled cube = compile_ids("lattice_cube.iq", rings_scene(1000, false, 0));
    REQUIRE(cube.result.exit_code == 0);
    CHECK_THAT(cube.result.code, Catch::Contains("1000 instances on a 10×10×10 lattice"));
    CHECK(loops_in_scene(cube.result.code) == 3);
}

TEST_CASE("a group's loop stays within llvmpipe's loop iterations however many steps the march takes", "[instancing][render]") {
    // trial76 N2: 60 bumpy balls, each its own r, a and f, on WebGL2 (sliders as uniforms): one group marched with
    // K ≈ 53 and 2,048 steps, its loop of 60 members 123,000 iterations a pixel where llvmpipe ends the invocation at
    // 65,535 (LP_MAX_TGSI_LOOP_ITERATIONS: every loop's iterations in all). The balls were drawn as square blocks
    // (22.6 dB against Shadertoy). The group's loop now runs several members a trip, within the budget. (Forty here:
    // from 48 members, kMinTree, the group's spheres derived over its members' values make a hierarchy instead.)
    std::string text =
        "[modules]\nbump = \"\"\"\nshape\nD = ‖p‖ - r + a sin(f p_1) sin(f p_2) sin(f p_3)\nsin from trigonometry\nwhere\n"
        "p ∈ ℝ³\nr ∈ [0.1, 2] default = 0.4\na ∈ [0, 0.5] default = 0.03\nf ∈ [0, 60] default = 10\n\"\"\"\n"
        "[camera]\nposition = [0, 6, -14]\ntarget = [0, 0, 0]\n[[lights]]\nposition = [-4, 8, -5]\n";
    for (int k = 0; k < 40; ++k)
        text += fmt::format("[[shapes]]\ntype = \"bump\"\nmaterial = \"lambert\"\ntransform = \"T(({:.3f}, 0, {:.2f}))\"\n"
                            "shape_params = {{ r = {:.3f}, a = {:.3f}, f = {} }}\n",
                            -6 + (k % 10) * 4.0 / 3.0, -3 + (k / 10) * 1.2, 0.2 + 0.02 * (k % 10), 0.01 * (k % 4), 3 + k % 7);
    CompileOptions o;
    o.target = Target::WebGL2;
    o.ids = true;
    Compiled c = compile_path(write_temp("bumps_40.iq", text), o);
    INFO(c.diagnostics);
    REQUIRE(c.result.exit_code == 0);
    const std::string& code = c.result.code;
    const size_t steps_at = code.find("const int IQC_MAX_STEPS = ");
    REQUIRE(steps_at != std::string::npos);
    const int steps = std::stoi(code.substr(steps_at + std::string("const int IQC_MAX_STEPS = ").size()));
    const size_t loop = code.find("40 instances (unrolled by ");
    INFO("IQC_MAX_STEPS " << steps);
    REQUIRE(loop != std::string::npos);
    const int unroll = std::stoi(code.substr(loop + std::string("40 instances (unrolled by ").size()));
    CHECK((40 + unroll - 1) / unroll * steps <= 60000);
    // The picture: the lit balls as Shadertoy's constants draw them (the march, normals and lights all count; an ids
    // render, the march alone, did not show the blocks). 96×54: 22 dB before, 42 dB now.
    const int W = 96, H = 54;
    o.ids = false;
    Compiled web = compile_path(write_temp("bumps_40.iq", text), o);
    Compiled toy = compile_path(write_temp("bumps_40.iq", text));
    REQUIRE(web.result.exit_code == 0);
    REQUIRE(toy.result.exit_code == 0);
    render::RenderResult a = render_compiled(web.result, W, H), b = render_compiled(toy.result, W, H);
    INFO(a.error << b.error);
    REQUIRE((a.ok && b.ok));
    REQUIRE(a.image.rgba.size() == b.image.rgba.size());
    const double psnr = psnr_8bit(a.image, b.image);
    INFO("PSNR " << psnr << " dB");
    CHECK(psnr >= 35);
}
