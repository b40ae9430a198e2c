#include "scene/Compile.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <set>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <memory>

#include "glsl/Emit.h"
#include "glsl/ShadertoyWrapper.h"
#include "glsl/Spirv.h"
#include "glsl/Wgsl.h"
#include "glsl/Validate.h"
#include "ir/Eval.h"
#include "ir/Intervals.h"
#include "ir/Pipeline.h"
#include "resources/Embedded.h"
#include "scene/Modules.h"
#include "scene/Plan.h"
#include "scene/SceneLower.h"
#include "scene/Template.h"
#include "sema/Builtins.h"
#include "source/Internal.h"

namespace iqc {

namespace {

// The most the default step cap grows for steps shortened by Lipschitz factors and non-uniform scales (the 128
// default becomes at most 2,048).
constexpr double kMaxStepGrowth = 16;

std::string vec3_literal(const std::array<double, 3>& v) { return glsl::constant(Type::vector(3), {v[0], v[1], v[2]}); }

// The scene's camera as the uniform targets take it (runtime_templates/scene.glsl), as the host sets it:
// iqc_camera_position (the eye), iqc_camera_basis (unit columns right, up, forward; world up +y, as
// iqc_look_at), iqc_camera_focal (1 / tan(fov / 2)) and iqc_projection (column-major, clip from view space
// looking down -z; from near = 1e-4 · max_dist to far = max_dist; only its depth rows matter to the shader).
// `zero_to_one`: Vulkan's depth range [0, 1], else OpenGL's [-1, 1].
std::vector<ShaderInputs::Uniform> camera_uniforms(const CameraDesc& cam, double max_dist, bool zero_to_one) {
    std::array<double, 3> f{}, up{0, 1, 0};
    double n = 0;
    for (int k = 0; k < 3; ++k) n += std::pow(cam.target[size_t(k)] - cam.position[size_t(k)], 2);
    n = std::sqrt(n);
    for (int k = 0; k < 3; ++k) f[size_t(k)] = n > 0 ? (cam.target[size_t(k)] - cam.position[size_t(k)]) / n : (k == 2 ? 1 : 0);
    if (std::fabs(f[1]) > 0.999) up = {0, 0, 1};
    auto cross = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
        return std::array<double, 3>{a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    };
    std::array<double, 3> r = cross(up, f);
    double rn = std::sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (double& x : r) x /= rn;
    std::array<double, 3> u = cross(f, r);
    double focal = 1.0 / std::tan(cam.fov * M_PI / 360.0);
    double near = 1e-4 * max_dist, far = max_dist;
    std::vector<double> projection(16, 0.0);
    projection[0] = focal;  // aspect 1: a host sets its own; the depth rows do not depend on it
    projection[5] = focal;
    projection[10] = zero_to_one ? far / (near - far) : (far + near) / (near - far);
    projection[11] = -1;
    projection[14] = zero_to_one ? far * near / (near - far) : 2 * far * near / (near - far);
    return {{"iqc_camera_position", {cam.position.begin(), cam.position.end()}, false},
            {"iqc_camera_basis", {r[0], r[1], r[2], u[0], u[1], u[2], f[0], f[1], f[2]}, false},
            {"iqc_camera_focal", {focal}, false},
            {"iqc_projection", projection, false}};
}

// --meta's "camera": the scene's camera and each camera uniform's default (a number for a float).
nlohmann::ordered_json camera_json(const CameraDesc& cam, const std::vector<ShaderInputs::Uniform>& uniforms) {
    nlohmann::ordered_json j;
    j["position"] = cam.position;
    j["target"] = cam.target;
    j["fov"] = cam.fov;
    j["orbit"] = cam.orbit;
    j["uniforms"] = {{"position", "iqc_camera_position"}, {"basis", "iqc_camera_basis"}, {"focal", "iqc_camera_focal"},
                     {"projection", "iqc_projection"}};
    nlohmann::ordered_json defaults;
    for (const auto& u : uniforms) defaults[u.name] = u.value.size() == 1 ? nlohmann::ordered_json(u.value[0]) : nlohmann::ordered_json(u.value);
    j["defaults"] = defaults;
    return j;
}

class SceneCompiler {
public:
    SceneCompiler(const SceneDesc& s, SourceManager& sm, Diagnostics& d, const CompileOptions& o)
        : s_(s), sm_(sm), d_(d), opts_(o) {}
    CompileResult run();
    CompileResult run_checked();

private:
    const SceneDesc& s_;
    SourceManager& sm_;
    Diagnostics& d_;
    const CompileOptions& opts_;
    ModuleLibrary lib_{sm_, d_, {std::filesystem::path(s_.path).parent_path().string()}};
    CompileResult res_;
    std::chrono::steady_clock::time_point clock_ = std::chrono::steady_clock::now();

    void lap(const std::string& name) {
        auto now = std::chrono::steady_clock::now();
        res_.pass_ms.push_back({name, std::chrono::duration<double, std::milli>(now - clock_).count()});
        clock_ = now;
    }
    March march() const { return opts_.oracle ? March::Sphere : opts_.march.value_or(s_.render.march); }
    Normals normals() const { return opts_.normals.value_or(s_.render.normals); }
    double hit() const { return opts_.hit.value_or(s_.render.hit); }
    std::vector<ShaderInputs::Uniform> camera() const {
        return camera_uniforms(s_.camera, s_.render.max_dist, through_spirv(opts_.target));
    }
    // `bound`: ten hit tolerances (at the farthest distance for a relative tolerance), and at least 0.1: a
    // march never stops on a bounding sphere, and the shape is evaluated wherever a hit is possible.
    double bound_margin() const { return std::max(0.1, 10 * hit() * (s_.render.hit_relative ? s_.render.max_dist : 1.0)); }
    // Twice the float spacing at the largest coordinate the camera reaches (its position; an orbit keeps its
    // distance to the target): the FAR tolerance's spacing at t = 0 (iqc_spacing).
    double spacing0() const {
        double radius = 0, reach = 0;
        for (int k = 0; k < 3; ++k) radius += std::pow(s_.camera.position[k] - s_.camera.target[k], 2);
        radius = std::sqrt(radius);
        for (int k = 0; k < 3; ++k)
            reach = std::max(reach, s_.camera.orbit ? std::fabs(s_.camera.target[k]) + radius : std::fabs(s_.camera.position[k]));
        return 2.4e-7 * reach;
    }
    // The scene box's level (SceneLowerOptions::box_level): above every value a sample outside the box could
    // be accepted at — ten hit tolerances at the farthest distance (and the FAR tolerance's four float
    // spacings), and the step cap's pixel cone at max_dist for images 360 rows tall or more
    // (iqc render's default; on smaller images a ray that runs out of steps beside a surface may differ).
    double box_level() const { return std::max(box_level_floor(), s_.render.max_dist * box_cone()); }
    // The level without the step cap's cone, and the cone's radius per unit of distance (360 rows).
    // Ten hit tolerances (not the `bound` margin's 0.1: a bound sphere's own box is grown by the level, and
    // outside the box the shapes' distances, which its distance bounds from below, exceed the level all the
    // same). The Menger sponge's box was ±1.10 for the hand-written reference's ±1.01: 5% of its frame.
    double box_level_floor() const {
        double far_tolerance = 4 * (spacing0() + 2.4e-7 * s_.render.max_dist);
        double tolerances = 10 * hit() * (s_.render.hit_relative ? s_.render.max_dist : 1.0);
        double bench = 10 * opts_.bench_max_hit * (s_.render.hit_relative ? s_.render.max_dist : 1.0);
        return std::max({tolerances, bench, 10 * far_tolerance});
    }
    double box_cone() const { return std::tan(s_.camera.fov * M_PI / 360.0) / 360; }

    SceneIR lower(const std::vector<InstancePlan>& plans);
    // Whether a march may start inside a shape (the march then tests its first sample's sign, a compare and a
    // select in every step). Not when every march starts at the camera (no reflection or refraction rays) and
    // the camera is fixed (Shadertoy without orbit: other targets move it by uniforms), the scene reads no
    // input (time, mouse) and its distance at the camera, in double precision, is above ten hit tolerances
    // and the float spacing there.
    bool march_may_start_inside(const SceneIR& scene, const std::set<std::string>& flags) const;
    bool optimize(SceneIR& scene);
    void warn_large_tables(const SceneIR& scene);
    void warn_idle_effects(const SceneIR& scene);
    std::string assemble(const SceneIR& scene, const SceneCode& code);
    // Whether every instance's distance is exact (its shape says `# exact` and its transform is a similarity
    // at the parameters' values and reads no input): only then may soft shadows use the improved penumbra
    // estimate, whose triangulation of consecutive spheres invents shadow from a mere bound.
    static bool exact_distances(const std::vector<InstancePlan>& plans);
    bool exact_ = false;
    bool segment_refused_ = false;  // march = "segment", but the segment pass derived no bounds
    // How much shorter than the distance to the nearest surface sphere tracing's steps may be: the largest
    // Lipschitz factor a distance is divided by, times the largest condition number of an instance's transform.
    double step_shortening_ = 1;
    // An instance whose glow the shader gathers: a glow that is not black, outside the per-instance baseline
    // and the debug views (which show values). The lowering emits iqc_distance_of for exactly these.
    bool gathers_glow(const InstanceDesc& in) const {
        return in.glow && (*in.glow)[0] + (*in.glow)[1] + (*in.glow)[2] > 0 && !opts_.per_instance &&
               s_.render.debug == DebugView::None;
    }
    void set_model(const SceneIR& scene);
    void warn_camera();
};

SceneIR SceneCompiler::lower(const std::vector<InstancePlan>& plans) {
    SceneLowerOptions lo;
    lo.params_constant = opts_.target == Target::Shadertoy;
    lo.analytic_normals = normals() == Normals::Analytic && !opts_.per_instance;
    lo.instance_normals = normals() != Normals::Analytic && !opts_.per_instance;
    for (const InstanceDesc& in : s_.instances) lo.distance_of |= gathers_glow(in);
    lo.segment = march() == March::Segment && !opts_.per_instance;
    lo.instrument = opts_.instrument || opts_.bench;
    lo.per_instance = opts_.per_instance;
    lo.reflections = s_.effects.reflections > 0;
    lo.refraction = s_.effects.refraction;
    // Soft shadows and AO read the distance's value: with `bound` spheres they read a lower bound there and
    // darken (the penumbra estimate); they get the scene without them.
    lo.unbounded_scene = (s_.effects.shadows == Shadows::Soft || s_.effects.ao) && !opts_.per_instance;
    lo.max_dist = s_.render.max_dist;
    if (march() == March::Fixed && !(s_.render.step > 0) && !opts_.per_instance && !opts_.oracle) {
        lo.thickness_level = hit();
        if (s_.render.hit_relative) lo.thickness_eye = s_.camera.position;  // (uniform targets: where it starts)
    }
    lo.bound_margin = bound_margin();
    lo.box_level = box_level();
    {
        // The cone's part of the level at the box's farthest point, where the camera cannot go anywhere (uniform
        // targets move it freely): Shadertoy's fixed camera, or its orbit around the target.
        lo.box_level_floor = box_level_floor();
        if (opts_.target == Target::Shadertoy) {
            lo.box_cone = box_cone();
            lo.box_eye = s_.camera.orbit ? s_.camera.target : s_.camera.position;
            if (s_.camera.orbit) {
                double r2 = 0;
                for (int k = 0; k < 3; ++k) r2 += std::pow(s_.camera.position[k] - s_.camera.target[k], 2);
                lo.box_eye_radius = std::sqrt(r2);
            }
        }
    }
    return lower_scene(s_, plans, lo);
}

// An effect the scene asks for that nothing in it can show is a located warning, not silence: shadows are
// cast toward lights and shade only materials a light reaches (those reading `P_L`); reflections and
// refraction need a material with `k_r`, `k_t`.
void SceneCompiler::warn_idle_effects(const SceneIR& scene) {
    const EffectsDesc& fx = s_.effects;
    bool shading_lights = false;
    for (const auto& l : s_.lights) {
        shading_lights |= l.kind == LightKind::Point || l.kind == LightKind::Sun;
        if ((l.kind == LightKind::Sky || l.kind == LightKind::Bounce) && !scene.binds_ambient)
            d_.warning(l.span, fmt::format("the {} light '{}' has no effect: no material has an ambient light colour `C_A` "
                                           "(the stdlib's pbr material has; see docs/look.md)",
                                           l.kind == LightKind::Sky ? "sky" : "bounce", l.name));
    }
    if (fx.shadows != Shadows::None) {
        if (!shading_lights)
            d_.warning(fx.shadows_span, "shadows have no effect: the scene has no point light or sun (shadows are cast toward "
                                        "each light's position or direction); add a [[lights]] table with a position");
        else if (!scene.has_shade_light)
            d_.warning(fx.shadows_span, "shadows have no effect: no material is lit by the lights (none has the light's "
                                        "position `P_L` as a parameter)");
    }
    if (fx.reflections > 0 && !scene.has_reflectivity)
        d_.warning(fx.reflections_span, "reflections have no effect: no material has a reflectivity `k_r`");
    if (fx.refraction && !scene.has_transmission)
        d_.warning(fx.refraction_span, "refraction has no effect: no material has a transmission `k_t` and an index `η`");
}

// The pass pipeline; range warnings become diagnostics (errors with --strict-ranges).
bool SceneCompiler::march_may_start_inside(const SceneIR& scene, const std::set<std::string>& flags) const {
    if (opts_.target != Target::Shadertoy || s_.camera.orbit || flags.count("BOUNCES") || opts_.per_instance) return true;
    // A camera outside the scene's box: every march starts where its ray enters the box (iqc_far), and there every
    // instance's distance is at least the box's level (ten hit tolerances or more; SceneIR::box), so no march
    // starts inside a shape, whatever the field does near the camera (100 tori on a lattice: its floors defeat
    // the interval test below).
    if (const auto& box = scene.box; box && flags.count("SCENE_BOX"))
        for (int a = 0; a < 3; ++a)
            if (s_.camera.position[size_t(a)] < box->first[size_t(a)] || s_.camera.position[size_t(a)] > box->second[size_t(a)])
                return false;
    const ir::Module& m = scene.module;
    bool steps = false;
    for (const ir::Function& f : m.functions)
        for (const ir::Instr& in : f.body)
            if (in.op == ir::Op::Input) return true;  // the distance at the camera changes with time or the mouse
            else if (in.op == ir::Op::Builtin) {
                const std::string& n = builtin(in.aux).name;
                steps |= n == "fract" || n == "floor" || n == "ceil" || n == "mod" || n == "round" || n == "sign" || n == "step" ||
                         n == "trunc";
            }
    int fn = m.find(ir::names::kScene);
    if (fn < 0) return true;
    const auto& eye = s_.camera.position;
    double reach = std::max({std::fabs(eye[0]), std::fabs(eye[1]), std::fabs(eye[2])});
    const double above = std::max(10 * hit(), 1e-5 * (1 + reach));
    if (steps) {
        // A step in the field (fract of a hashed sin, floor, mod): float and double may land on different sides
        // of it, and the double-precision value at the camera proves nothing about the shader's (a noise terrain
        // 0.03 below the camera in double was 0.28 above it in float: a new-user trial). Interval arithmetic over
        // a box around the camera, 10⁻³ of its distance from the origin wide (a hash's argument then spans whole
        // periods, and its interval every value), must keep the distance above the level: a Menger sponge's
        // mod-folded holes are cut from a box the camera is outside of (max(box, holes) ≥ box).
        const double r = 1e-3 * (1 + reach);
        std::vector<ir::Interval> box;
        for (int a = 0; a < 3; ++a) box.push_back({eye[size_t(a)] - r, eye[size_t(a)] + r});
        long work = 200000;
        auto b = ir::interval_analysis(m, fn, {box}, {}, 16, &work);
        const ir::Function& f = m.functions[size_t(fn)];
        if (b.size() <= f.result || b[f.result].c.empty() || !(b[f.result].c[0].lo > above)) return true;
    }
    try {
        ir::Value d = ir::evaluate(m, fn, {ir::Value{Type::vector(3), {eye[0], eye[1], eye[2]}}});
        return !(d.v.size() >= 1 && d.v[0] > above);
    } catch (...) {  // an evaluation past its budget: keep the test
        return true;
    }
}

bool SceneCompiler::optimize(SceneIR& scene) {
    ir::PipelineOptions po;
    po.verify_each = opts_.verify_each;
    po.dump_after = opts_.dump_after;
    po.inject_fault = opts_.inject_fault;
    ir::PipelineResult pr = ir::run_pipeline(scene.module, po);
    for (const auto& issue : pr.range_issues) {
        if (opts_.strict_ranges) d_.error(issue.span, issue.message + " (--strict-ranges)");
        else d_.warning(issue.span, issue.message);
    }
    for (const auto& w : pr.warnings) d_.warning(w.span, w.message);
    step_shortening_ *= pr.lipschitz_largest;
    segment_refused_ = !pr.segment_refused.empty();
    if (segment_refused_)
        d_.warning(s_.render.march_span, "segment tracing takes sphere-tracing steps in this scene: " + pr.segment_refused);
    for (const auto& [name, ms] : pr.pass_ms) res_.pass_ms.push_back({"  " + name, ms});
    res_.lipschitz = pr.lipschitz;
    if (opts_.dump_ir) {
        res_.ir = opts_.dump_after.empty() ? ir::print(scene.module) : pr.dump;
        std::string notes;
        for (const auto& line : pr.lipschitz) notes += "; lipschitz: " + line + "\n";
        bool open = !scene.box;
        for (size_t a = 0; a < 3 && scene.box; ++a) open |= std::isinf(scene.box->first[a]) || std::isinf(scene.box->second[a]);
        notes += fmt::format("; scene box: {} ({} analyses of shapes' boxes)\n", !scene.box ? "none" : open ? "open" : "closed", scene.box_analyses);
        for (const auto& rw : pr.rewrites)
            notes += fmt::format("; stable: {} in {}{}\n", rw.what, rw.function, rw.where.valid() ? " at " + sm_.location(rw.where) : "");
        res_.ir = notes + res_.ir;
    }
    return true;
}

// On Shadertoy every table is code: a constant array of more than 4,096 vec4 slots (a mat3 takes 3, a vector or
// number 1) is more than llvmpipe keeps as uniform storage, and its indexing compiles for minutes (1,300 tilted
// tori, mat3[1300] = 3,900 slots: 7.9 s; 1,380: over a minute). Said where the table's item starts.
void SceneCompiler::warn_large_tables(const SceneIR& scene) {
    if (opts_.target != Target::Shadertoy) return;
    constexpr long long kSlots = 4096;
    const ir::Module& m = scene.module;
    std::vector<bool> used(m.globals.size(), false);
    for (const auto& f : m.functions)
        for (const auto& in : f.body)
            if (in.op == ir::Op::Global && in.aux >= 0 && size_t(in.aux) < used.size()) used[size_t(in.aux)] = true;
    std::set<std::pair<uint32_t, uint32_t>> said;  // one warning per item
    for (size_t g = 0; g < m.globals.size(); ++g) {
        const ir::Global& gl = m.globals[g];
        if (!used[g] || !gl.type.is_array()) continue;
        const long long slots = (long long)gl.type.count * (gl.type.elem == Type::Matrix ? gl.type.cols : 1);
        if (slots <= kSlots) continue;
        auto at = scene.global_spans.find(int(g));
        if (at == scene.global_spans.end() || !said.insert({at->second.file, at->second.begin}).second) continue;
        d_.warning(at->second, fmt::format("on Shadertoy the table '{}' ({} elements, {} vec4 slots) is code: past {} slots a driver may "
                                           "compile its indexing for minutes (llvmpipe does); --target webgl2 keeps tables in uniform "
                                           "blocks or a texture",
                                           gl.name, gl.type.count, slots, kSlots));
    }
}

std::string SceneCompiler::assemble(const SceneIR& scene, const SceneCode& code) {
    const RenderDesc& render = s_.render;
    const EffectsDesc& fx = s_.effects;
    int max_steps = opts_.max_steps.value_or(render.max_steps);
    // max_steps is a budget of steps as long as the distance to the nearest surface. Where a distance is divided by
    // a Lipschitz factor K, or a non-uniform scale multiplies it by 1/σ_max, steps are up to that factor F shorter,
    // and rays that the budget would carry to a surface stop short of it and show the background (a new user's
    // trial: S((0.05, 1, 1)) on a box cut a funnel of sky through the ground behind it; a twisted plate with K 23.8
    // lost its top; dotted sky along a terrain's ridges). The default grows by F (at most 16×); a max_steps the
    // scene sets is kept as it is (the hard cases set theirs and agree with the double-precision reference).
    double shortening = std::min(kMaxStepGrowth, step_shortening_);
    const int budget_steps = max_steps;  // before the growth: what `fixed`'s default step divides the reach by
    std::string max_steps_doc;
    if (!opts_.max_steps && !render.max_steps_span.valid() && shortening > 1.05) {
        max_steps_doc = fmt::format("  // max_steps {} × {:.3g}: steps are up to that much shorter than the distance to a "
                                    "surface here (a Lipschitz factor, a non-uniform scale)",
                                    max_steps, shortening);
        max_steps = int(std::min<double>(kMaxStepsSetting, std::ceil(max_steps * shortening)));
    }
    bool lights = scene.lights > 0;
    double focal = 1.0 / std::tan(s_.camera.fov * M_PI / 360.0);
    TemplateArgs ta;
    auto& V = ta.values;
    auto& F = ta.flags;
    V["TITLE"] = glsl::comment_text(s_.title);
    V["VERSION"] = IQC_VERSION;
    V["SOURCE"] = glsl::comment_text(std::filesystem::path(s_.path).filename().string());
    V["TARGET"] = target_name(opts_.target);
    V["MAX_STEPS"] = std::to_string(max_steps);
    V["MAX_STEPS_DOC"] = max_steps_doc;
    V["MAX_DIST"] = glsl::float_literal(render.max_dist);
    V["HIT"] = glsl::float_literal(hit());
    V["HIT_DOC"] = render.hit_relative ? "hit tolerance per unit of distance along the ray" : "hit tolerance (world units)";
    V["BACKGROUND"] = vec3_literal(render.background);
    V["CAMERA_POSITION"] = vec3_literal(s_.camera.position);
    V["CAMERA_TARGET"] = vec3_literal(s_.camera.target);
    V["CAMERA_FOCAL"] = glsl::float_literal(focal);
    // `fixed`'s step by default: the longest way a march can go over the step cap. Marches start where the ray
    // enters the scene's box and end where it leaves, so where the box is closed on every side that way is at
    // most its diagonal: a camera 12,000 units from a torus took steps of 156 (max_dist / max_steps) through a
    // box 2.8 wide and drew nothing.
    double fixed_reach = render.max_dist;
    if (const auto& box = scene.box; box && !opts_.per_instance) {
        double d2 = 0;
        bool closed = true;
        for (size_t k = 0; k < 3; ++k) {
            closed &= std::isfinite(box->first[k]) && std::isfinite(box->second[k]);
            d2 += (box->second[k] - box->first[k]) * (box->second[k] - box->first[k]);
        }
        if (closed) fixed_reach = std::min(fixed_reach, std::sqrt(d2));
    }
    // (Over the step budget as the scene gives it, not as grown for shortened steps: `fixed` takes no step by a
    // distance, and 16x the samples per ray on a scene with a thin scale bought nothing; its loop, and the sphere-
    // traced shadows', keep the grown cap.)
    V["FIXED_STEP"] = glsl::float_literal(render.step > 0 ? render.step : fixed_reach / budget_steps);
    // A default step longer than the thinnest instance can take a ray over it: a wall 0.2 thick drew nothing
    // with steps of 0.47 (max_dist 60 over 128 steps; a trial's finding, stop 44). Steps from each ray's own way
    // through the box were tried (stop 45): thin walls in open boxes were drawn, but every ray that missed took
    // all max_steps samples (a trial: 15x a pipe scene's evaluations for the same picture), a ground made every
    // downward ray's way max_dist again, and a finite panel's closed box kept its diagonal's step. A fixed step
    // is the scene's choice of cost against what it can miss: it is said, with the step that would see the part.
    // (A step between half the thickness and all of it still samples a slab on every ray: warned there, a plate
    // 0.02 thick showed 2 pixels of difference either way in a trial.) The step advised is half the thickness:
    // rays that cross a curved part near its edge (a tube's, a shell's) run a shorter way through it.
    if (scene.thinnest && !(render.step > 0) && fixed_reach / max_steps > scene.thinnest->thickness) {
        // Half the thickness, rounded down to two significant digits (a step to write in the scene).
        const double half = scene.thinnest->thickness / 2, unit = std::pow(10.0, std::floor(std::log10(half)) - 1);
        const double fine = std::floor(half / unit) * unit;
        const long steps = long(std::ceil(fixed_reach / fine));
        d_.warning(scene.thinnest->span,
                   fmt::format("`march = \"fixed\"` steps {} by default ({} {:g} / max_steps {}), longer than the thickness of '{}' "
                               "({:.4g} with the hit test's band, by interval arithmetic on its distance): a ray can step over it without a "
                               "sample inside. "
                               "Set `step` under [render] to at most {}{}",
                               glsl::float_literal(fixed_reach / max_steps),
                               fixed_reach < render.max_dist ? "the scene box's diagonal" : "max_dist", fixed_reach, max_steps,
                               scene.thinnest->name, scene.thinnest->thickness, glsl::float_literal(fine),
                               steps <= kMaxStepsSetting
                                   ? fmt::format(" (and max_steps to {} to reach as far)", steps)
                                   : fmt::format(" (to reach as far it would take {} steps, over max_steps' limit of {}: a "
                                                 "smaller max_dist, or `march = \"sphere\"`)", steps, kMaxStepsSetting)));
    }
    V["RELAXATION"] = glsl::float_literal(render.relaxation);
    V["SHADOW_K"] = glsl::float_literal(fx.shadow_softness);
    V["FOG"] = glsl::float_literal(fx.fog);
    V["FOG_COLOR"] = vec3_literal(fx.fog_color.value_or(render.background));
    V["BOUNCES"] = std::to_string(fx.reflections + (fx.refraction ? 2 : 0));
    V["AA"] = std::to_string(fx.antialias);
    V["LIGHTS"] = std::to_string(scene.lights);
    V["POINT_LIGHTS"] = std::to_string(scene.point_lights);
    if (scene.lights > scene.point_lights) F.insert("SUNS");
    V["ZENITH"] = vec3_literal(render.zenith);
    V["GROUND"] = vec3_literal(render.has_ground ? render.ground : render.background);
    if (render.sky_gradient) F.insert("SKY");
    if (render.sky_gradient && render.stars > 0) F.insert("STARS");
    V["STARS"] = glsl::float_literal(0.03 * render.stars);
    V["DECLARATIONS"] = code.declarations;
    V["FUNCTIONS"] = code.functions;
    V["INSTANCES"] = std::to_string(scene.instances);
    switch (opts_.target) {
        case Target::Shadertoy: F.insert("SHADERTOY"); break;
        case Target::WebGL2:
        case Target::ThreeJS: F.insert("WEBGL2"); break;
        case Target::GLSL330: F.insert("GLSL330"); break;
        case Target::SPIRV:
        case Target::HLSL:
        case Target::WGSL: F.insert("VULKAN"); break;
    }
    // Depth for compositing with meshes: every uniform target's colour build (not the probes).
    if (opts_.target != Target::Shadertoy && !opts_.instrument && !opts_.geometry && !opts_.ids && !opts_.bench) F.insert("DEPTH");
    {
        double r2 = 0;
        for (int k = 0; k < 3; ++k) r2 += std::pow(s_.camera.position[size_t(k)] - s_.camera.target[size_t(k)], 2);
        V["ORBIT_RADIUS"] = glsl::float_literal(std::sqrt(r2));
    }
    V["BOX_LO"] = V["BOX_HI"] = V["BOX_SLABS"] = "";
    V["T_FAR"] = "IQC_MAX_DIST";  // where a march ends: iqc_far's t_far where there is a box
    // The scene's box (SceneIR::box): rays are clipped to it.
    if (const auto& box = scene.box; box && !opts_.per_instance) {
        // ±∞ sides as ±1e30: the slab test's products stay ±∞ or finite (never 0·∞ unless a ray starts on a plane).
        auto side = [](const std::array<double, 3>& v, double inf) {
            std::array<double, 3> w = v;
            for (double& x : w) x = std::isinf(x) ? std::copysign(inf, x) : x;
            return w;
        };
        V["BOX_LO"] = vec3_literal(side(box->first, 1e30));
        V["BOX_HI"] = vec3_literal(side(box->second, 1e30));
        // iqc_far's slab test on the axes where the box is bounded on either side (on the others every ray lies
        // within the slab: its t interval is all of ℝ, and the test cost llvmpipe's compile 3% on a ground plane).
        // (where the box follows the sliders, SceneIR::box_at_defaults, iqc_box_lo() and iqc_box_hi() pick it: its axes
        // too, the whole's may be open on every side)
        const bool follows = scene.box_at_defaults.has_value() && scene.module.find(ir::names::kBoxLo) >= 0;
        std::string axes;
        for (int a = 0; a < 3; ++a)
            if (std::isfinite(box->first[size_t(a)]) || std::isfinite(box->second[size_t(a)]) ||
                (follows && (std::isfinite(scene.box_at_defaults->first[size_t(a)]) || std::isfinite(scene.box_at_defaults->second[size_t(a)]))))
                axes += "xyz"[a];
        // One slab per bounded axis: float, vec2 or vec3 arithmetic on those components (all of rd where all three).
        std::string& slabs = V["BOX_SLABS"];
        const size_t n = axes.size();
        if (n == 0) {
            slabs = "    float t_in = 0.0, t_out = IQC_MAX_DIST;";
        } else {
            const std::string type = n == 1 ? "float" : "vec" + std::to_string(n), sw = n == 3 ? "" : "." + axes;
            const std::string lo = follows ? std::string(ir::names::kBoxLo) + "()" : "IQC_BOX_LO",
                              hi = follows ? std::string(ir::names::kBoxHi) + "()" : "IQC_BOX_HI";
            slabs = "    " + type + " m = 1.0 / rd" + sw + ";\n    " + type + " a = (" + lo + sw + " - ro" + sw +
                    ") * m, b = (" + hi + sw + " - ro" + sw + ") * m;\n";
            if (n == 1)
                slabs += "    float t_in = min(a, b), t_out = min(max(a, b), IQC_MAX_DIST);";
            else
                slabs += "    " + type + " n = min(a, b), f = max(a, b);\n" +
                         (n == 2 ? "    float t_in = max(n.x, n.y), t_out = min(min(f.x, f.y), IQC_MAX_DIST);"
                                 : "    float t_in = max(max(n.x, n.y), n.z), t_out = min(min(min(f.x, f.y), f.z), IQC_MAX_DIST);");
        }
        F.insert("SCENE_BOX");
        V["T_FAR"] = "t_far";
    }
    static const char* marches[] = {"MARCH_FIXED", "MARCH_SPHERE", "MARCH_RELAXED", "MARCH_AUTO", "MARCH_SEGMENT"};
    // Segment tracing is sphere tracing with another step: one march function with both flags (sphere tracing
    // alone where the segment pass derived no bounds).
    if (!opts_.per_instance && march() == March::Segment) F.insert(segment_refused_ ? "MARCH_SPHERE" : "MARCH_SEGMENT");
    F.insert(opts_.per_instance ? "PER_INSTANCE"
             : opts_.oracle     ? "MARCH_ORACLE"
                                : marches[int(march() == March::Segment ? March::Sphere : march())]);
    if (opts_.per_instance) F.insert("LIPSCHITZ");
    // The step cap's rules (iqc_cone, iqc_nearness): only the distance-bound marches use them.
    if (!opts_.per_instance && march() != March::Fixed) F.insert("STEP_CAP_CONE");
    static const char* normal_flags[] = {"NORMALS_CENTRAL", "NORMALS_FORWARD", "NORMALS_TETRAHEDRON", "NORMALS_ANALYTIC"};
    F.insert(normal_flags[int(opts_.per_instance && normals() == Normals::Analytic ? Normals::Tetrahedron : normals())]);
    if (opts_.per_instance || normals() != Normals::Analytic) F.insert("NORMALS_FINITE");
    if (!opts_.per_instance && normals() != Normals::Analytic) F.insert("INSTANCE_TAPS");
    if (render.hit_relative) F.insert("HIT_RELATIVE");
    {
        // Float spacing far from the origin (FAR): twice the ulp at the largest coordinate the camera reaches
        // (its position; an orbit keeps its distance to the target). Emitted only where it can matter: where
        // spacing along the longest ray reaches a quarter of the hit tolerance.
        double spacing0 = this->spacing0();
        V["SPACING0"] = glsl::float_literal(spacing0);
        // A relative tolerance (hit · t) grows with t as the spacing does: compare at t = 1 and per unit of t.
        bool far = render.hit_relative ? 4 * std::max(spacing0, 2.4e-7) > 0.25 * hit()
                                       : 4 * (spacing0 + 2.4e-7 * render.max_dist) > 0.25 * hit();
        if (far) F.insert("FAR");
        if (!far && !render.hit_relative) F.insert("EPS_CONSTANT");  // iqc_eps(t) is IQC_HIT: no division per step
        V["NORMAL_STEP"] = far ? "iqc_normal_step(t)" : "0.5 * iqc_eps(t)";
    }
    // Some instance's distance is divided by a Lipschitz factor: the hit test multiplies it back.
    if (int lf = scene.module.find(ir::names::kLipschitz); !opts_.per_instance && lf >= 0 && scene.module.functions[size_t(lf)].entry)
        F.insert("HIT_SCALE");
    if (scene.has_shade_light) F.insert("SHADE_LIGHT");
    if (scene.binds_footprint) F.insert("FOOTPRINT");  // some material filters by the pixel's footprint w_P
    // Glows: a table of the glowing instances (id, colour, radius) the primary ray gathers in one loop.
    for (const char* k : {"GLOW_COUNT", "GLOW_IDS", "GLOW_COLORS", "GLOW_RADII"}) V[k] = "";
    std::vector<std::string> ids, colours, radii;
    for (size_t i = 0; i < s_.instances.size(); ++i) {
        const InstanceDesc& in = s_.instances[i];
        if (!gathers_glow(in)) continue;
        ids.push_back(std::to_string(scene.instance_ids[i]));
        colours.push_back(vec3_literal(*in.glow));
        radii.push_back(glsl::float_literal(in.glow_radius));
    }
    if (!ids.empty()) {
        F.insert("GLOW");
        V["GLOW_COUNT"] = std::to_string(ids.size());
        V["GLOW_IDS"] = fmt::format("{}", fmt::join(ids, ", "));
        V["GLOW_COLORS"] = fmt::format("{}", fmt::join(colours, ", "));
        V["GLOW_RADII"] = fmt::format("{}", fmt::join(radii, ", "));
    }
    if (fx.shadows != Shadows::None && lights && scene.has_shade_light) {
        F.insert("SHADOWS");
        F.insert(fx.shadows == Shadows::Hard ? "SHADOWS_HARD" : "SHADOWS_SOFT");
        if (fx.shadows != Shadows::Hard && exact_) F.insert("SHADOWS_IMPROVED");
    }
    if (fx.ao) F.insert("AO");
    if (F.count("SHADOWS_SOFT") || F.count("AO")) {
        F.insert("SCENE_EFFECTS");
        if (scene.module.find(ir::names::kSceneUnbounded) >= 0) F.insert("SCENE_UNBOUNDED");
    }
    if (fx.fog > 0) F.insert("FOG");
    if (fx.fog > 0 && fx.fog_exp2) F.insert("FOG_EXP2");
    if (fx.reflections > 0 && scene.has_reflectivity) F.insert("REFLECTIONS");
    if (fx.refraction && scene.has_transmission) F.insert("REFRACTION");
    if (F.count("REFLECTIONS") || F.count("REFRACTION")) F.insert("BOUNCES");
    // The path's length so far: the footprint's cone and the fog grow along all of it.
    if (F.count("BOUNCES") && (F.count("FOOTPRINT") || F.count("FOG"))) F.insert("PATH");
    if (fx.antialias > 1) F.insert("AA");
    // A sky shows each sun (needs the lights' functions: some material is lit).
    if (F.count("SKY") && F.count("SUNS") && F.count("SHADE_LIGHT")) F.insert("SUN_DISC");
    // The thesis's look (I♥IQ documents, modules alone) reflects by k_r alone; scenes get Fresnel: more
    // reflection at grazing angles, and glass that reflects as it refracts.
    if (F.count("BOUNCES") && !s_.thesis_look) {
        F.insert("FRESNEL");
        if (F.count("REFRACTION")) F.insert("FRESNEL_GLANCE");
        if (scene.has_reflectivity) F.insert("REFLECTIVITY");
        // Mirrors and glass show the point lights (a sun is in the sky already, where there is one).
        if (F.count("SHADE_LIGHT") && scene.point_lights > 0) F.insert("GLINTS");
    }
    if (march_may_start_inside(scene, F)) F.insert("INSIDE_START");
    // The output transform: exposure, tone map, sRGB (not for the debug views, which show values).
    V["EXPOSURE"] = glsl::float_literal(render.exposure);
    V["VIGNETTE"] = glsl::float_literal(render.vignette);
    V["CONTRAST"] = glsl::float_literal(render.contrast);
    if (render.debug == DebugView::None) {
        if (render.exposure != 1) F.insert("EXPOSURE");
        if (render.vignette > 0) F.insert("VIGNETTE");
        if (render.contrast > 0) F.insert("CONTRAST");
        if (render.tonemap == RenderDesc::Tonemap::ACES) F.insert("TONEMAP_ACES");
        if (render.tonemap == RenderDesc::Tonemap::Reinhard) F.insert("TONEMAP_REINHARD");
        if (s_.srgb()) F.insert("SRGB");
        if (F.count("EXPOSURE") || F.count("TONEMAP_ACES") || F.count("TONEMAP_REINHARD") || F.count("SRGB") || F.count("VIGNETTE") ||
            F.count("CONTRAST"))
            F.insert("OUTPUT");
        // sRGB and the contrast curve clamp to [0, 1] and keep their result there (up to rounding, which an 8-bit
        // target's conversion clamps), as the vignette's darkening (a factor in [1 - vignette, 1]) does: the
        // output needs no second clamp (1.3% of llvmpipe's compile of the grazing-plane bench scene).
        if (F.count("SRGB") || F.count("CONTRAST")) F.insert("OUTPUT_IN_RANGE");
    }
    static const char* debug_flags[] = {"", "DEBUG_NORMALS", "DEBUG_STEPS", "DEBUG_DEPTH"};
    if (render.debug != DebugView::None) F.insert(debug_flags[int(render.debug)]);
    // The mouse orbit is the shader's on Shadertoy only: every other target takes the host's camera (the html
    // page orbits it in JavaScript, --meta "camera": "orbit").
    if (s_.camera.orbit && opts_.target == Target::Shadertoy) F.insert("ORBIT");
    if (opts_.target == Target::Shadertoy) F.insert("LOOK_AT");
    if (scene.module.find(ir::names::kPrepare) >= 0) F.insert("PREPARE");
    if (opts_.instrument || opts_.bench) F.insert("INSTRUMENT");
    if (opts_.geometry || opts_.ids || opts_.bench) F.insert("GEOMETRY");
    if (opts_.ids) F.insert("IDS");
    if (opts_.bench) F.insert("BENCH");
    nlohmann::ordered_json j;
    j["title"] = s_.title;
    j["target"] = target_name(opts_.target);
    // The Shadertoy inputs the picture depends on (a host redraws a scene without iTime only when something
    // changes): the time and the mouse where the optimized IR reads them, the mouse also for an orbit camera.
    // iFrame only keeps loops from unrolling (min(iFrame, 0)): 0 when unset, as hosts may leave it.
    bool reads[2] = {false, false};
    for (const auto& fn : scene.module.functions)
        for (const auto& in : fn.body)
            if (in.op == ir::Op::Input && in.aux >= 0 && in.aux < 2) reads[in.aux] = true;
    j["inputs"] = nlohmann::ordered_json::array({"iResolution"});
    if (reads[0]) j["inputs"].push_back("iTime");
    if (reads[1] || (s_.camera.orbit && opts_.target == Target::Shadertoy)) j["inputs"].push_back("iMouse");
    // How the shader encodes its colour: "srgb" (colours it takes are linear) or "linear" (I♥IQ's documents).
    j["output"] = s_.srgb() ? "srgb" : "linear";
    if (opts_.target != Target::Shadertoy) j["camera"] = camera_json(s_.camera, camera());
    if (through_spirv(opts_.target)) {
        // The template's IqcInputs block (std140, set 0, binding 0): what the host writes every frame.
        nlohmann::ordered_json members = nlohmann::ordered_json::array();
        auto member = [&](const char* name, const char* type, int offset) {
            nlohmann::ordered_json m;
            m["name"] = name;
            m["type"] = type;
            m["offset"] = offset;
            if (type == std::string("mat3") || type == std::string("mat4")) m["column_stride"] = 16;
            members.push_back(m);
        };
        member("iqc_camera_basis", "mat3", 0);
        member("iqc_camera_position", "vec3", 48);
        member("iqc_camera_focal", "float", 60);
        member("iqc_projection", "mat4", 64);
        member("iResolution", "vec3", 128);
        member("iTime", "float", 140);
        member("iMouse", "vec4", 144);
        member("iFrame", "int", 160);
        j["inputs_block"] = {{"name", "IqcInputs"}, {"set", 0}, {"binding", 0}, {"bytes", 164}, {"members", members}};
    }
    j["parameters"] = code.parameters;
    j["lights"] = code.lights;
    j["blocks"] = code.blocks;
    j["texture"] = code.texture;
    res_.meta = j.dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace) + "\n";  // invalid UTF-8: U+FFFD
    return expand_template(std::string(*embedded_file("runtime_templates/scene.glsl")), ta);
}

bool SceneCompiler::exact_distances(const std::vector<InstancePlan>& plans) {
    for (const auto& p : plans) {
        if (!p.shape || p.shape->exactness != "exact") return false;
        if (!p.has_transform) continue;
        if (p.transform_uses_inputs) return false;
        // L Lᵀ = s² I: a rotation times a uniform scale keeps a distance exact (after the scale correction).
        const auto& L = p.inv_linear;
        double s2 = L[0] * L[0] + L[1] * L[1] + L[2] * L[2];
        for (int r = 0; r < 3; ++r)
            for (int c = 0; c < 3; ++c) {
                double dot = L[size_t(3 * r)] * L[size_t(3 * c)] + L[size_t(3 * r + 1)] * L[size_t(3 * c + 1)] +
                             L[size_t(3 * r + 2)] * L[size_t(3 * c + 2)];
                if (std::fabs(dot - (r == c ? s2 : 0)) > 1e-9 * std::max(1.0, s2)) return false;
            }
    }
    return true;
}

// The same scene in double precision: the optimized IR the shader came from, run by the evaluator.
// What rays can resolve from where the camera stands, said at its `position`: a camera within the hit
// tolerance of a surface stops every ray where it starts (a scene 1e-4 across under the default hit 1e-3 is one
// grey picture), and 32-bit floats farther out than their spacing reaches the tolerance lose the surface's
// detail (a scene 1e5 from the origin: 8% of its pixels differ from the same scene at the origin).
void SceneCompiler::warn_camera() {
    const CameraDesc& cam = s_.camera;
    const RenderDesc& r = s_.render;
    if (!cam.position_span.valid() || !res_.model) return;
    if (!r.hit_relative) {
        double d0 = NAN;
        try {
            d0 = res_.model->distance(cam.position);
        } catch (...) {  // a recurrence past the evaluator's budget: nothing to say
        }
        if (std::isfinite(d0) && std::fabs(d0) < r.hit)
            d_.warning(cam.position_span, fmt::format("the camera is {:.3g} from the nearest surface, within the hit tolerance ({:g}): "
                                                      "every ray stops where it starts; lower `hit` in [render] below the scene's "
                                                      "size, or use hit_mode = \"relative\"",
                                                      std::fabs(d0), r.hit));
    }
    double far = 0;
    for (double c : cam.position) far = std::max(far, std::fabs(c));
    double spacing = double(std::nextafter(float(far), INFINITY)) - double(float(far));
    double gap = 0;
    for (int k = 0; k < 3; ++k) gap += (cam.target[size_t(k)] - cam.position[size_t(k)]) * (cam.target[size_t(k)] - cam.position[size_t(k)]);
    double tolerance = r.hit_relative ? r.hit * std::sqrt(gap) : r.hit;
    if (spacing > tolerance)
        d_.warning(cam.position_span, fmt::format("the camera is {:.3g} from the origin, where 32-bit floats (what shaders compute in) "
                                                  "are {:.3g} apart, coarser than the hit tolerance ({:.3g}): surfaces are found only to "
                                                  "about that, and their detail and shading suffer; move the scene and the camera "
                                                  "near the origin",
                                                  far, spacing, tolerance));
}

void SceneCompiler::set_model(const SceneIR& scene) {
    auto model = std::make_shared<SceneModel>();
    model->ir = scene.module;
    model->camera = s_.camera;
    model->render = s_.render;
    model->init();
    res_.model = std::move(model);
    res_.blends = !s_.blends.empty();
}

// A function grown past the IR's size limit (ir::SizeLimit, from planning, lowering or a pass) is the
// input's error, located where the lowering was.
CompileResult SceneCompiler::run() {
    try {
        return run_checked();
    } catch (const ir::SizeLimit& limit) {
        if (limit.span.valid()) d_.error(limit.span, ir::size_limit_message());
        else d_.error_nospan(ir::size_limit_message());
        CompileResult r;
        r.exit_code = 1;
        return r;
    }
}

CompileResult SceneCompiler::run_checked() {
    size_t before = d_.error_count();
    for (const auto& m : s_.modules) lib_.add(m);  // a document's blocks with one name are already one module
    std::vector<InstancePlan> plans;
    bool planned = plan_instances(s_, lib_, sm_, d_, plans, opts_.strict_ranges);
    for (const auto& p : plans) step_shortening_ = std::max(step_shortening_, p.step_shortening);
    lap("parse + check + transforms");
    if (!planned || d_.error_count() != before) return std::move(res_);
    try {
        SceneIR scene = lower(plans);
        for (const auto& [span, message] : scene.warnings) d_.warning(span, message);
        lap("lower to IR");
        warn_idle_effects(scene);
        optimize(scene);
        warn_large_tables(scene);
        lap("pass pipeline");
        if (d_.error_count() != before) return std::move(res_);
        BackendOptions bo;
        bo.constants = opts_.target == Target::Shadertoy;
        bo.vulkan = through_spirv(opts_.target);
        bo.blocks = opts_.target != Target::ThreeJS;
        bo.instrument = opts_.instrument || opts_.bench;
        {
            // (the step cap as assemble() grows it; shadow marches take as many; AO 5 samples, the normal 4 taps)
            const RenderDesc& render = s_.render;
            double steps = opts_.max_steps.value_or(render.max_steps);
            if (!opts_.max_steps && !render.max_steps_span.valid())
                steps = std::min<double>(kMaxStepsSetting, std::ceil(steps * std::min(kMaxStepGrowth, step_shortening_)));
            const EffectsDesc& fx = s_.effects;
            double per_ray = steps + 4 + (fx.ao ? 5 : 0) + (fx.shadows != Shadows::None ? double(s_.lights.size()) * steps : 0);
            double rays = (1.0 + fx.reflections + (fx.refraction ? 2 : 0)) * double(fx.antialias) * double(fx.antialias);
            bo.evaluations_per_pixel = per_ray * rays;
        }
        for (const auto& p : plans) {
            bo.comments[p.shape->ast.name] = "shape " + p.shape->ast.name;
            if (p.material) {
                const std::string& m = p.material->ast.name;
                bo.comments[m] = "material " + m;
                bo.comments[m + ".ambient"] = "material " + m + ": the terms of C that read no light (iqc_shade)";
                bo.comments[m + ".light"] = "material " + m + ": the terms of C that read the light (iqc_shade_light)";
            }
            bo.comments[p.name + ".transform"] = "transform of " + p.name;
        }
        exact_ = exact_distances(plans);
        SceneCode code = emit_scene(scene, bo, d_);
        if (d_.error_count() != before) return std::move(res_);
        std::string shader = assemble(scene, code);
        lap("GLSL backend + assembly");
        if (opts_.inject_fault == "glslang") shader += "\nthis line is not GLSL;\n";
        glsl::ValidationResult v;
        switch (opts_.target) {
            case Target::Shadertoy: v = glsl::validate_fragment(glsl::wrap_shadertoy(shader), glsl::Profile::Es300); break;
            case Target::WebGL2:
            case Target::ThreeJS: v = glsl::validate_fragment(shader, glsl::Profile::Es300); break;
            case Target::GLSL330: v = glsl::validate_fragment(shader, glsl::Profile::Core330); break;
            case Target::SPIRV:
            case Target::HLSL:
            case Target::WGSL: {
                glsl::SpirvResult spv = glsl::compile_vulkan_fragment(shader);
                v.ok = spv.ok;
                v.log = spv.log;
                res_.spirv = std::move(spv.words);
                break;
            }
        }
        lap("glslang validation");
        if (!v.ok) {
            res_.exit_code = 3;
            res_.internal = internal_error_message(through_spirv(opts_.target)
                                                       ? "glslang or SPIRV-Tools rejected the generated Vulkan shader"
                                                       : "glslang rejected the generated shader") +
                            ":\n" + v.log;
            res_.spirv.clear();
            return std::move(res_);
        }
        if (opts_.target == Target::HLSL) {
            glsl::HlslResult h = glsl::spirv_to_hlsl(res_.spirv);
            lap("SPIRV-Cross + HLSL check");
            if (!h.ok) {
                res_.exit_code = 3;
                res_.internal = internal_error_message("the HLSL cross-compiled from the shader's SPIR-V was rejected") + ":\n" + h.log;
                res_.spirv.clear();
                return std::move(res_);
            }
            // SPIRV-Cross writes no provenance: the header every text target has.
            shader = "// " + glsl::comment_text(s_.title) + "\n// Generated by iqc " IQC_VERSION " from " +
                     glsl::comment_text(std::filesystem::path(s_.path).filename().string()) +
                     " (hlsl): Vulkan GLSL compiled to SPIR-V, cross-compiled by SPIRV-Cross.\n// Inputs: cbuffer IqcInputs "
                     "(b0), the parameters' cbuffers (b1...), layout in --meta (docs/engines.md). Do not edit: regenerate "
                     "with iqc.\n" + h.text;
        }
        if (opts_.target == Target::WGSL) {
            // the fault test: an opcode the translation does not know (OpImageQueryLevels) appended to the module
            if (opts_.inject_fault == "wgsl" && res_.spirv.size() > 5) {
                uint32_t id = res_.spirv[3]++;
                res_.spirv.insert(res_.spirv.end(), {(4u << 16) | 106u, 1u, id, 3u});
            }
            glsl::WgslResult w = glsl::spirv_to_wgsl(res_.spirv);
            lap("SPIR-V to WGSL");
            res_.spirv.clear();
            if (!w.ok) {
                res_.exit_code = 3;
                res_.internal = internal_error_message("the shader's SPIR-V could not be translated to WGSL") + ":\n" + w.log;
                return std::move(res_);
            }
            shader = "// " + glsl::comment_text(s_.title) + "\n// Generated by iqc " IQC_VERSION " from " +
                     glsl::comment_text(std::filesystem::path(s_.path).filename().string()) +
                     " (wgsl): Vulkan GLSL compiled to SPIR-V, translated to WGSL.\n// Entry points: vs_main (a full-screen "
                     "triangle, 3 vertices) and fs_main. Inputs: IqcInputs (@group(0) @binding(0)), the parameters' uniform "
                     "blocks (@binding(1)...), std140 layout in --meta (docs/engines.md). Do not edit: regenerate with iqc.\n" +
                     w.text;
        }
        res_.code = std::move(shader);
        res_.inputs = std::move(code.inputs);
        if (opts_.target != Target::Shadertoy) res_.inputs.camera = camera();
        set_model(scene);
        warn_camera();
        res_.exit_code = 0;
    } catch (const InternalError& e) {
        res_.exit_code = 3;
        res_.internal = internal_error_message(e.what());
    }
    return std::move(res_);
}

}  // namespace

const char* target_name(Target t) {
    switch (t) {
        case Target::Shadertoy: return "shadertoy";
        case Target::WebGL2: return "webgl2";
        case Target::GLSL330: return "glsl330";
        case Target::SPIRV: return "spirv";
        case Target::HLSL: return "hlsl";
        case Target::WGSL: return "wgsl";
        case Target::ThreeJS: return "threejs";
    }
    return "?";
}

CompileResult compile_scene(const SceneDesc& scene, SourceManager& sm, Diagnostics& diags, const CompileOptions& opts) {
    SceneCompiler c(scene, sm, diags, opts);
    return c.run();
}

CompileResult compile_file(const std::string& path, SourceManager& sm, Diagnostics& diags, const CompileOptions& opts) {
    auto t0 = std::chrono::steady_clock::now();
    SceneDesc scene;
    if (!load_scene(path, sm, diags, scene)) return {};
    double load_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    CompileResult r = compile_scene(scene, sm, diags, opts);
    r.pass_ms.insert(r.pass_ms.begin(), {"read scene", load_ms});
    return r;
}

}  // namespace iqc
