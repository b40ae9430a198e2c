#include "scene/SceneLower.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <optional>
#include <tuple>
#include <fmt/format.h>
#include <fmt/ranges.h>
#include <set>

#include "glsl/Emit.h"
#include "glsl/Names.h"
#include "scene/Bvh.h"
#include "ir/Builder.h"
#include "ir/Eval.h"
#include "ir/Lower.h"
#include "ir/Support.h"

namespace iqc {

using namespace conventions;
using ir::Builder;
using ir::CompareKind;
using ir::Global;
using ir::Op;
using ir::ValueId;

namespace {

std::string param_comment(const ParamInfo& p) {
    // A sequence's bounds are per element (x_i ∈ [-1, 1]×[-1, 1]×[-1, 1], not its 3·n intervals in a row): one
    // element's where all are alike, else each component's hull over the elements.
    const size_t n = p.type.is_array() ? size_t(std::max(1, p.type.element().components())) : p.lo.size();
    const bool sequence = p.type.is_array() && !p.seq_index.empty() && n > 0 && p.lo.size() % n == 0 && p.hi.size() == p.lo.size();
    std::string s = fmt::format("{}{} ∈ ", p.name, sequence ? "_" + p.seq_index : "");
    if (p.bounded) {
        std::vector<double> lo = p.lo, hi = p.hi;
        bool alike = true;
        if (sequence) {
            lo.assign(p.lo.begin(), p.lo.begin() + long(n));
            hi.assign(p.hi.begin(), p.hi.begin() + long(n));
            for (size_t i = n; i < p.lo.size(); ++i) {
                alike = alike && p.lo[i] == lo[i % n] && p.hi[i] == hi[i % n];
                lo[i % n] = std::min(lo[i % n], p.lo[i]);
                hi[i % n] = std::max(hi[i % n], p.hi[i]);
            }
        }
        std::vector<std::string> iv;
        for (size_t i = 0; i < lo.size(); ++i) iv.push_back(fmt::format("[{}, {}]", lo[i], hi[i]));
        s += fmt::format("{}", fmt::join(iv, "×"));
        if (!alike) s += " (the elements' hull)";
    } else {
        s += p.type.str();
    }
    if (!p.description.empty()) s += ": " + p.description;
    return s;
}

bool is_identity3(const std::vector<double>& L) {
    for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c)
            if (std::fabs(L[size_t(r * 3 + c)] - (r == c ? 1.0 : 0.0)) > 1e-12) return false;
    return true;
}

bool is_zero(const std::vector<double>& v) {
    for (double x : v)
        if (std::fabs(x) > 1e-12) return false;
    return true;
}

// A per-instance quantity of an item: one value (a global), or one per member (an array global read at k).
struct Field {
    int global = -1;
    bool array = false;
};

// A run of instances lowered together: one instance, or a group (a loop over per-instance data).
struct Item {
    std::vector<size_t> members;  // plan indices
    bool group = false;
    int id = 0;                   // the first member's instance id
    std::string name;             // the instance's name, or the group's
    Field to_object, offset, scale, bound;
    std::vector<Field> shape_params, material_params;  // per module parameter (-1 global: bound by the renderer)
    std::vector<Field> transform_params;               // runtime transforms: their parameters
    int transform_fn = -1;
    int distance_fn = -1;
    int unbounded_fn = -1;  // the distance without the `bound` sphere (iqc_scene_unbounded), or -1
    int lipschitz_global = -1;  // <name>_lipschitz: the factor its distance is divided by (the lipschitz pass sets it)
    // A group whose members all have `bound`, from kMinTree members: the bounding-volume hierarchy iqc_scene traverses,
    // its node tables per level (centre, radius, first child, child count) and the members in leaf order.
    BoundsTree tree;
    bool derived_bound = false;  // its members' bound spheres were derived from the shape (no `bound` written)
    // Where sliders are uniforms and the spheres over their ranges are too wide, derived over the hull of the members'
    // values: the prepared global (1 while every member's values are within that hull, iqc_prepare's loop) guards the
    // hierarchy's skips and the spheres' stand-ins; -1 where the spheres hold over the ranges.
    int hull_valid = -1;
    struct TreeLevel {
        Field center, half, first, count;
    };
    std::vector<TreeLevel> tree_globals;
    Field tree_order;
    bool leaf_ordered = false;  // the members are in the hierarchy's leaf order (no tree_order table)
    // A group with `bound` whose spheres fill a lattice (InstanceLattice): iqc_scene finds the members near a
    // point by arithmetic instead of the hierarchy.
    InstanceLattice lattice;
    bool exact = false;  // the shape says `# exact`: skipping far subtrees leaves iqc_scene_unbounded's value as is
    // A group whose world → object maps differ in few entries (tori tilted about one axis: 4 of 9, two values up
    // to sign): the map is built per member from its entries, each a constant (linear_global -1: linear_value)
    // or linear_sign times a table's value (linear_global: a scalar table, or component linear_component of a
    // table of vectors). Reading a whole mat3 table is 9 gathers per member.
    bool linear_split = false;
    std::array<int, 9> linear_global{};
    std::array<int, 9> linear_component{};  // -1: linear_global is a scalar table; else the component of its vectors
    std::array<double, 9> linear_value{}, linear_sign{};
    // A lattice group whose members sit on their cells' centres (to float precision): the distance of member k
    // at a point already moved to its cell's centre (q = L_k·(p − centre), no offset table), or -1.
    int centred_fn = -1;
    int blend = -1;      // a single instance in a [[blends]] entry: the scene and the shading see the blend instead
};

// A group of this many members or more, each with `bound`, is traversed as a bounding-volume hierarchy (fewer:
// one loop, each member testing its own sphere); nodes have at most kTreeBranching children. Measured on
// rings with `bound` (llvmpipe, frames after the first): at 1,000 boxes of 8 children 36 ms, of 16 40 ms,
// spheres of 16 children 75 ms (they overlap around a lattice's clusters), no hierarchy 356 ms; the loop
// wins below about 40 members (32 rings: 12–18 ms against 18–21; 64 rings: 51–57 against 23–39).
constexpr size_t kMinTree = 48;
// Where tables are constants in the code (Shadertoy), a hierarchy over more members is not built: its tables
// (the members in leaf order, the nodes' boxes) grow with the count, and llvmpipe's compile with them faster
// than linearly (2,000 rings: 2.8 s in all; 4,000: 7.5 s; 10,000: minutes). A lattice without one stays a
// few formulas. Targets with uniform blocks or the data texture build it at any size.
constexpr size_t kMaxTreeInCode = 2048;
constexpr int kTreeBranching = 8;
// A lattice is used where its spheres' radius is at most this many times its smallest spacing (else a point
// near the lattice is near too many cells, and the hierarchy visits fewer).
constexpr double kLatticeMostRadius = 1.5;

class SceneLowering {
public:
    SceneLowering(const SceneDesc& s, const std::vector<InstancePlan>& p, const SceneLowerOptions& o) : s_(s), plans_(p), o_(o) {}

    SceneIR run() {
        bind_lights_ = !s_.lights.empty();
        for (const auto& l : s_.lights) {
            lights_ |= l.kind == LightKind::Point || l.kind == LightKind::Sun;
            ambient_lights_ |= l.kind == LightKind::Sky || l.kind == LightKind::Bounce;
        }
        m_.constant_parameters = o_.params_constant;
        make_items();
        if (!o_.per_instance) scene_box();
        if (o_.thickness_level > 0) thinnest();
        declare_lights();
        for (Item& it : items_) declare_item(it);
        for (Item& it : items_) {
            it.distance_fn = item_distance(it, true);
            if (lattice_centred(it)) it.centred_fn = item_distance(it, true, true);
        }
        scene_function(true);
        bool any_bound = false;
        for (const Item& it : items_) any_bound |= it.bound.global >= 0;
        if (o_.unbounded_scene && any_bound) {
            for (Item& it : items_)
                it.unbounded_fn = it.bound.global >= 0 || o_.instrument ? item_distance(it, false) : it.distance_fn;
            scene_function(false);
        }
        // Glows march an instance's own distance far from it: the true one, not its bound sphere's.
        if (o_.distance_of && any_bound)
            for (Item& it : items_)
                if (it.unbounded_fn < 0) it.unbounded_fn = it.bound.global >= 0 ? item_distance(it, false) : it.distance_fn;
        lipschitz_function();
        if (o_.analytic_normals || o_.instance_normals || o_.distance_of || o_.segment) gradient_functions();
        shade_functions();
        // k_r: for mirrors (reflections) and for glass, whose Fresnel reflection it raises (refraction).
        if (o_.reflections || o_.refraction) out_.has_reflectivity = material_property(ir::names::kReflectivity);
        if (o_.refraction) out_.has_transmission = material_property(ir::names::kTransmission);
        prepare_function();
        hull_functions();
        box_functions();
        if (o_.per_instance) per_instance_functions();
        out_.instances = int(plans_.size());
        out_.instance_ids.assign(plans_.size(), -1);
        for (const Item& it : items_)
            for (size_t m = 0; m < it.members.size(); ++m) out_.instance_ids[it.members[m]] = it.id + int(m);
        for (size_t i = 0; i < plans_.size(); ++i)
            if (plan_box_[i]) {
                std::array<double, 6> b;
                for (size_t a = 0; a < 3; ++a) {
                    b[a] = std::isfinite((*plan_box_[i])[a].lo) ? (*plan_box_[i])[a].lo : -1e30;
                    b[3 + a] = std::isfinite((*plan_box_[i])[a].hi) ? (*plan_box_[i])[a].hi : 1e30;
                }
                m_.instance_boxes[out_.instance_ids[i]] = b;
            }
        out_.lights = int(light_pos_.size());
        out_.point_lights = point_lights_;
        return std::move(out_);
    }

private:
    const SceneDesc& s_;
    const std::vector<InstancePlan>& plans_;
    std::vector<double> derived_bound_ = std::vector<double>(plans_.size(), 0.0);  // per plan; 0: none
    // Per plan: 1 where derived_bound_ holds only over the hull of its group's values (Item::hull_valid guards it at run
    // time): the scene box and the Lipschitz analysis do not read it.
    std::vector<char> hull_bound_ = std::vector<char>(plans_.size(), 0);
    // The most members iqc_prepare's loops test (prepare_within: a group's hull, the box's window), once per pixel.
    static constexpr size_t kMaxHullMembers = 1024;
    // Per plan: its world box from scene_box (none where it found none, or stopped before it).
    std::vector<std::optional<std::array<ir::Interval, 3>>> plan_box_ = std::vector<std::optional<std::array<ir::Interval, 3>>>(plans_.size());
    const SceneLowerOptions& o_;
    SceneIR out_;
    ir::Module& m_ = out_.module;
    LowerContext ctx_{out_.module, {}, {}};
    std::vector<Item> items_;
    bool lights_ = false;          // point lights or suns: bound to materials' P_L, C_L
    bool bind_lights_ = false;     // the scene has [[lights]]: P_L and C_L are the lights' (none: no direct light)
    bool ambient_lights_ = false;  // sky or bounce lights: bound to materials' C_A
    std::set<std::string> global_names_;
    // The shading lights' globals, point lights first, then suns (whose "position" global is their direction).
    std::vector<int> light_pos_, light_col_;
    int point_lights_ = 0;
    struct AmbientLight {
        LightKind kind;
        int color = -1, direction = -1;  // globals (direction: bounce lights)
    };
    std::vector<AmbientLight> ambient_;
    int ambient_fn_ = -1;
    std::map<std::pair<int, bool>, int> parts_;  // (material function, light part?) -> material_part
    std::vector<std::vector<size_t>> blend_items_;  // per [[blends]] entry: its members' items, in instance order
    bool narrow_ = false;  // shape_intervals takes each slider near its default (the box at the sliders' defaults)
    double box_tau_ = 0;   // the level of the last scene_box_at
    std::string owner_;  // the item being declared (Global::owner)
    Span owner_span_;    // its first instance's `type` (SceneIR::global_spans)

    const InstancePlan& plan(size_t i) const { return plans_[i]; }
    // An instance's bounding-sphere radius: its `bound`, or the one derived for its group (0: none).
    double bound_of(size_t i) const { return plan(i).desc->bound > 0 ? plan(i).desc->bound : derived_bound_[i]; }

    // The intervals of a shape's parameters over the members of a group (their values' hull; on targets with
    // sliders, their slider ranges too); the query point's entry is left unbounded. Nothing when a parameter
    // has no range on a slider target (an input).
    std::optional<std::vector<std::vector<ir::Interval>>> shape_intervals(const std::vector<size_t>& members, bool hull_only = false) {
        const InstancePlan& first = plan(members[0]);
        std::vector<ir::ValueBounds> ranges = parameter_bounds(*first.shape);
        std::vector<std::vector<ir::Interval>> params(first.shape->params.size());
        for (size_t i = 0; i < params.size(); ++i) {
            if (int(i) == first.query) continue;
            for (size_t c = 0; c < plan(members[0]).shape_values[i].size(); ++c) params[i].push_back(value_hull(members, i, c));
            if (!o_.params_constant && !hull_only) {
                const ir::ValueBounds& r = ranges[i];
                if (r.input || r.lo.size() != params[i].size()) return std::nullopt;
                for (size_t c = 0; c < params[i].size(); ++c) {
                    ir::Interval range{r.lo[c], r.hi[c]};
                    if (narrow_) {
                        const std::optional<ir::Interval> near = near_default(range, params[i][c]);
                        if (near) range = *near;
                    }
                    params[i][c] = ir::iv::hull(params[i][c], range);
                }
            }
        }
        params[size_t(first.query)].assign(3, {});
        return params;
    }

    // The hull of parameter i's component c over the members, each value with its float (the shader's constant:
    // 10000000.49 is 10000000 there).
    ir::Interval value_hull(const std::vector<size_t>& members, size_t i, size_t c) const {
        ir::Interval h{INFINITY, -INFINITY};
        for (size_t mi : members) {
            const auto& v = plan(mi).shape_values[i];
            if (c < v.size()) h = ir::iv::hull(h, ir::iv::hull({v[c], v[c]}, {double(float(v[c])), double(float(v[c]))}));
        }
        return h;
    }

    // A slider's range near its value v (the hull of its members' values): within 1/64 of the range of v, where the range
    // is finite and wider than that (nothing: the whole range).
    static std::optional<ir::Interval> near_default(ir::Interval range, ir::Interval v) {
        const double w = (range.hi - range.lo) / 64;
        if (!std::isfinite(w) || !(w > 0)) return std::nullopt;
        ir::Interval near{std::max(range.lo, v.lo - w), std::min(range.hi, v.hi + w)};
        if (!(near.lo <= near.hi) || (near.lo <= range.lo && near.hi >= range.hi)) return std::nullopt;
        return near;
    }

    // A bounding-sphere radius for every member of a group without `bound`: the shape's extent by interval
    // arithmetic (ir/Support.h) over the hull of the members' parameter values (on targets with sliders, their
    // slider ranges too), or nothing (an unbounded shape such as a plane; a parameter without a range).
    std::optional<double> derived_bound(const std::vector<size_t>& members, bool hull_only = false) {
        const InstancePlan& first = plan(members[0]);
        int fn = lower_module_cached(*first.shape, ctx_);
        auto params = shape_intervals(members, hull_only);
        if (!params) return std::nullopt;
        auto R = ir::support_radius(m_, fn, first.query, std::move(*params));
        if (!R) return R;
        // Spheres that overlap a lot make a hierarchy that skips little and walks many members per step
        // (llvmpipe ends a pixel's shader after 65,535 loop iterations): a ring's slider range up to (2, 2) makes
        // it 4 units wide on a grid of 1. Used only while the spheres fill their box less than twice over.
        std::vector<BoundingSphere> spheres;
        double volume = 0;
        for (size_t mi : members) {
            spheres.push_back(world_sphere(plan(mi).inv_linear, plan(mi).inv_offset, *R));
            volume += 4.0 / 3.0 * M_PI * std::pow(spheres.back().radius, 3);
        }
        std::vector<BoundingBox> boxes;
        for (const auto& sp : spheres) boxes.push_back(box_of(sp));
        BoundingBox all = enclosing_box(boxes);
        // (over the members' hull, half full at most: off the hull, and even on it where many spheres overlap, the
        // hierarchy's levels walk every node and member, loops llvmpipe cannot unroll within its iterations; 48 bumps
        // whose r, a and f spread over their ranges, spheres 1.07 times their box, drew black blocks at the defaults
        // on WebGL2, 32.6 dB where the flat loop gives 51; trial78 #2)
        if (volume > (hull_only ? 0.5 : 2) * 8 * all.half[0] * all.half[1] * all.half[2]) return std::nullopt;
        return R;
    }
    // The scene's box (SceneIR::box): the union of every instance's world box, where its nearness (its
    // distance in world units, before any Lipschitz division: what the hit test and the step cap read) can be
    // within the `bound` margin of 0: the shape's own box (ir/Support.h's support_box in object space, once per
    // group over its members' parameters) mapped to the world through its affine transform (an unbounded side
    // stays unbounded where the map mixes it into a world axis); with a bound sphere (written or derived), that
    // box and the sphere's box, whichever is narrower on each side. No box when any instance has none: a
    // transform that moves at run time,
    // a smooth blend (its members' distances are divided by Lipschitz factors the passes derive later), or a
    // side unbounded on every axis.
    void scene_box() {
        scene_box_whole();
        if (o_.params_constant) return;
        // (without a box over the sliders' ranges, one at their defaults still clips rays while they are there: a
        // smooth union whose blend k ∈ [0, 10] reaches 0, dividing by it, had none, and its rays that missed marched
        // 427 steps a pixel where Shadertoy's took 20 (trial76, N4); not where no box can be: a transform that moves
        // at run time, a blend)
        if (!out_.box)
            for (size_t i = 0; i < plans_.size(); ++i)
                if (runtime_transform(plan(i)) || plan(i).blend >= 0) return;
        // (only where some shape has a slider near_default narrows: the Menger sponge has none, and its second analysis
        // doubled the lowering)
        bool any = false;
        std::set<const CheckedModule*> seen;
        for (size_t i = 0; i < plans_.size() && !any; ++i) {
            if (!seen.insert(plan(i).shape).second) continue;
            const std::vector<ir::ValueBounds> ranges = parameter_bounds(*plan(i).shape);
            for (size_t k = 0; k < ranges.size() && !any; ++k)
                for (size_t c = 0; c < ranges[k].lo.size() && !ranges[k].input && int(k) != plan(i).query && c < ranges[k].hi.size(); ++c)
                    any = any || near_default({ranges[k].lo[c], ranges[k].hi[c]}, {ranges[k].lo[c], ranges[k].lo[c]}).has_value();
        }
        if (!any) return;
        // Where sliders are uniforms: the box with each slider near its default, at the level the whole's was found at.
        const auto whole = out_.box;
        const auto instance_boxes = plan_box_;
        const int analyses = out_.box_analyses;
        narrow_ = true;
        scene_box_at(box_tau_);
        narrow_ = false;
        auto near = out_.box;
        out_.box = whole;
        plan_box_ = instance_boxes;
        out_.box_analyses += analyses;
        if (!near) return;
        if (!whole) {  // (the whole's box open on every side; the defaults' where it has a side)
            bool bounded = false;
            for (size_t a = 0; a < 3; ++a) bounded |= std::isfinite(near->first[a]) || std::isfinite(near->second[a]);
            if (!bounded) return;
            out_.box = std::pair<std::array<double, 3>, std::array<double, 3>>{{-INFINITY, -INFINITY, -INFINITY}, {INFINITY, INFINITY, INFINITY}};
            out_.box_at_defaults = near;
            return;
        }
        // Kept where some bounded side moves in by over 2% of the box's extent on that axis (of the side's distance from
        // the origin, at least 1, where the other side is unbounded: a terrain's top).
        bool narrower = false;
        for (size_t a = 0; a < 3; ++a) {
            const double lo = whole->first[a], hi = whole->second[a];
            if (near->first[a] < lo || near->second[a] > hi) return;  // (never wider: a narrower range's box)
            auto scale = [&](double side) { return std::isfinite(hi - lo) ? hi - lo : std::max(1.0, std::fabs(side)); };
            narrower |= std::isfinite(lo) && near->first[a] - lo > 0.02 * scale(lo);
            narrower |= std::isfinite(hi) && hi - near->second[a] > 0.02 * scale(hi);
        }
        if (narrower) out_.box_at_defaults = near;
    }

    void scene_box_whole() {
        if (!o_.box_eye || !(o_.box_cone > 0) || o_.box_level_floor >= o_.box_level) {
            scene_box_at(o_.box_level);
            return;
        }
        // The level the box's farthest point from the camera needs (the pixel cone there), from the floor up: the
        // box at a level holds every sample a march takes within it, and a march ends where it leaves the box.
        double tau = o_.box_level_floor;
        for (int round = 0; round < 3; ++round) {
            // An open scene box ends the rounds, and this round's boxes are recomputed at box_level: stop at the
            // first instance that opens it (examples/christmas_tree.iq's open tree and hills: half of lowering).
            scene_box_at(tau, true);
            if (!out_.box) break;
            double far = 0;
            for (int corner = 0; corner < 8; ++corner) {
                double d2 = 0;
                for (size_t a = 0; a < 3; ++a) {
                    double x = (corner >> a) & 1 ? out_.box->second[a] : out_.box->first[a];
                    d2 += std::pow(x - (*o_.box_eye)[a], 2);
                }
                far = std::max(far, std::sqrt(d2));
            }
            double need = o_.box_cone * (far + o_.box_eye_radius);
            if (need <= tau) return;  // (an open side: far is ∞, and the cone at max_dist stands)
            if (!std::isfinite(need) || need >= o_.box_level) break;
            tau = need * 1.05;  // the box grows with the level: a little more, so the next round holds
        }
        scene_box_at(o_.box_level);
    }

    // The boxes at level tau. `stop_when_open`: return without a scene box as soon as an instance leaves it
    // open (no box, or an unbounded side), analysing first the shapes whose boxes a quick test finds open.
    void scene_box_at(double tau, bool stop_when_open = false) {
        box_tau_ = tau;
        const double inf = INFINITY;
        out_.box.reset();
        for (auto& b : plan_box_) b.reset();
        std::array<double, 3> lo{inf, inf, inf}, hi{-inf, -inf, -inf};
        auto add = [&](size_t plan_index, const std::array<ir::Interval, 3>& w) {
            plan_box_[plan_index] = w;
            for (size_t a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], w[a].lo);
                hi[a] = std::max(hi[a], w[a].hi);
            }
        };
        // Instances of one shape: analysed together (over their parameters' hull) when many, else each alone. In
        // order of the shapes' first appearance (not of their modules' addresses, which vary from run to run).
        std::vector<std::pair<const CheckedModule*, std::vector<size_t>>> kinds;
        // An instance with a bound sphere: the sphere's world box, narrowed by the shape's own box where the
        // analysis finds one (inside the sphere the nearness is the shape's).
        std::map<size_t, std::array<ir::Interval, 3>> sphere_box;
        for (size_t i = 0; i < plans_.size(); ++i) {
            const InstancePlan& p = plan(i);
            if (runtime_transform(p) || p.blend >= 0) return;
            if (bound_of(i) > 0 && !hull_bound_[i]) {
                // Outside its sphere the instance's nearness is (|q| - R)·scale (q in object space): within tau
                // inside the object-space ball R + tau/scale, mapped to the world (a non-uniform scale
                // stretches it more along some axes than the scale says).
                BoundingBox b = box_of(world_sphere(p.inv_linear, p.inv_offset, bound_of(i) + tau / std::max(p.scale, 1e-9)));
                std::array<ir::Interval, 3> w;
                for (size_t a = 0; a < 3; ++a) w[a] = {b.center[a] - b.half[a], b.center[a] + b.half[a]};
                sphere_box[i] = w;
            }
            auto kind = std::find_if(kinds.begin(), kinds.end(), [&](const auto& k) { return k.first == p.shape; });
            if (kind == kinds.end()) kind = kinds.insert(kinds.end(), {p.shape, {}});
            kind->second.push_back(i);
        }
        // An instance's world box: its sphere's narrowed by `shape` (nothing: the sphere's; without a sphere,
        // nothing means no scene box).
        auto place = [&](size_t i, const std::optional<std::array<ir::Interval, 3>>& shape) {
            auto it = sphere_box.find(i);
            if (it == sphere_box.end()) {
                if (!shape) return false;
                add(i, *shape);
                return true;
            }
            std::array<ir::Interval, 3> w = it->second;
            if (shape)
                for (size_t a = 0; a < 3; ++a) {
                    ir::Interval x{std::max(w[a].lo, (*shape)[a].lo), std::min(w[a].hi, (*shape)[a].hi)};
                    if (x.lo <= x.hi) w[a] = x;
                }
            add(i, w);
            return true;
        };
        // Analysed once per shape and parameter values (instances that differ only in their transform share
        // one object box), and once over the hull of all values where more than four values differ.
        std::vector<std::vector<size_t>> sets;
        for (const auto& [shape, members] : kinds) {
            std::map<std::vector<std::vector<double>>, std::vector<size_t>> by_values;
            for (size_t mi : members) by_values[plan(mi).shape_values].push_back(mi);
            if (by_values.size() > 4) sets.push_back(members);
            else
                for (auto& [values, same] : by_values) sets.push_back(same);
        }
        // Every instance's own box is found even where another's is not (segment tracing skips an instance's
        // bounds outside its box: Module::instance_boxes); the scene's box needs them all.
        // The object-space level of a set: the nearness is the object distance times the map's scale, within tau
        // where the object distance is within tau / scale (the smallest scale of the members).
        auto object_level = [&](const std::vector<size_t>& members) {
            double scale = 1;
            for (size_t mi : members) scale = std::min(scale, plan(mi).scale);
            return tau / std::max(scale, 1e-9);
        };
        if (stop_when_open) {
            // Sets without spheres whose boxes are likely open first (a stable order otherwise).
            std::vector<char> open(sets.size(), 0);
            for (size_t k = 0; k < sets.size(); ++k) {
                bool spheres = true;
                for (size_t mi : sets[k]) spheres &= sphere_box.count(mi) > 0;
                if (spheres) continue;
                auto params = shape_intervals(sets[k]);
                const InstancePlan& first = plan(sets[k][0]);
                open[k] = !params || ir::support_box_open(m_, lower_module_cached(*first.shape, ctx_), first.query,
                                                          std::move(*params), object_level(sets[k]));
            }
            std::vector<size_t> order(sets.size());
            for (size_t k = 0; k < order.size(); ++k) order[k] = k;
            std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) { return open[x] > open[y]; });
            std::vector<std::vector<size_t>> sorted;
            for (size_t k : order) sorted.push_back(std::move(sets[k]));
            sets = std::move(sorted);
        }
        auto opened = [&] {
            for (size_t a = 0; a < 3; ++a)
                if (lo[a] == -inf || hi[a] == inf) return true;
            return false;
        };
        bool every = true;
        for (const auto& members : sets) {
            if (stop_when_open && (!every || opened())) return;
            const InstancePlan& first = plan(members[0]);
            int fn = lower_module_cached(*first.shape, ctx_);
            auto params = shape_intervals(members);
            std::optional<ir::SupportBox> box;
            // (the box at the sliders' defaults with a quarter of the work: it only narrows the whole's where it is found
            // in that; with the whole's, the Christmas tree's lowering took 150 ms more for a box top of 16.9 against
            // 10⁶ that changed no step from its camera)
            if (params) box = ir::support_box(m_, fn, first.query, std::move(*params), object_level(members), 48, 16, narrow_ ? 375000 : 1500000);
            ++out_.box_analyses;
            for (size_t mi : members) {
                const InstancePlan& p = plan(mi);
                if (!box) {
                    every &= place(mi, std::nullopt);
                    continue;
                }
                // object = L·world + o, so world = L⁻¹(object − o): each world axis an interval sum over the box.
                bool singular = false;
                std::vector<double> Li = ir::mat_inverse(p.inv_linear, 3, &singular);
                if (singular) {
                    every &= place(mi, std::nullopt);
                    continue;
                }
                // An unbounded object axis mixed into a world axis by a coefficient that is rounding (cos(π/2) =
                // 6·10⁻¹⁷: a wall turned by R_y(π/2) lost its bounded axis, and the scene its box): over the world
                // points float32 tells apart (|w| ≤ kFloatWorld, or 1000 max_dists) the object coordinate
                // x = L·w + o moves the world one by at most |Li|·‖L's row‖·|w|; where that is below a thousandth
                // of the level, the interval grows by it instead of opening.
                constexpr double kFloatWorld = 1e8;  // float32's spacing there is 8
                const double world = std::max(kFloatWorld, 1e3 * o_.max_dist);
                std::array<ir::Interval, 3> w;
                for (size_t r = 0; r < 3; ++r) {
                    ir::Interval sum{0, 0};
                    double drift = 0;
                    for (size_t c = 0; c < 3; ++c) {
                        const double l = Li[r * 3 + c];
                        if (l == 0) continue;  // an unbounded object axis the map leaves out
                        if (!std::isfinite(box->lo[c]) || !std::isfinite(box->hi[c])) {
                            const double row = std::hypot(p.inv_linear[c * 3], p.inv_linear[c * 3 + 1], p.inv_linear[c * 3 + 2]);
                            const double moved = std::fabs(l) * row * world;
                            if (moved <= 1e-3 * tau) {
                                drift += moved;
                                continue;
                            }
                        }
                        ir::Interval x{box->lo[c] - p.inv_offset[c], box->hi[c] - p.inv_offset[c]};
                        sum = ir::iv::add(sum, ir::iv::mul({l, l}, x));
                    }
                    w[r] = {sum.lo - drift, sum.hi + drift};
                }
                place(mi, w);
            }
        }
        if (!every) return;
        bool bounded = false;
        for (size_t a = 0; a < 3; ++a) bounded |= std::isfinite(lo[a]) || std::isfinite(hi[a]);
        if (!bounded) return;
        out_.box = {lo, hi};
    }
    // SceneIR::thinnest: per shape, one analysis per distinct parameter values (at most 8 sets a shape and 32 in
    // all, each with a small budget: a warning needs one thin part, and 200 shapes of a kind each cost 5x the
    // compile in a trial). Each set's box at the hit level in object space (support_box: the hit test's band
    // included, as a fixed march sees it), its sides' world widths through the members' transforms (a slab
    // |x_a| ≤ w/2 maps to one w / ‖row a of the world → object map‖ thick: a scale that stretches it counts),
    // and, where the map keeps shapes (a rotation and a uniform scale) and the box is closed, twice the depth
    // of the solid (deepest_bound: a shell's, a tube's, a frame's thickness, which the box does not show).
    // Transforms that move at run time are taken at their values at time 0 and the sliders' defaults.
    void thinnest() {
        std::vector<std::pair<const CheckedModule*, std::map<std::vector<std::vector<double>>, std::vector<size_t>>>> kinds;
        for (size_t i = 0; i < plans_.size(); ++i) {
            const InstancePlan& p = plan(i);
            auto kind = std::find_if(kinds.begin(), kinds.end(), [&](const auto& k) { return k.first == p.shape; });
            if (kind == kinds.end()) kind = kinds.insert(kinds.end(), {p.shape, {}});
            if (kind->second.size() < 8 || kind->second.count(p.shape_values)) kind->second[p.shape_values].push_back(i);
        }
        constexpr long kWork = 300000;  // about 3 ms an analysis
        int analyses = 0;
        for (const auto& [shape, sets] : kinds)
            for (const auto& [values, members] : sets) {
                if (++analyses > 32) return;
                const InstancePlan& first = plan(members[0]);
                std::vector<std::vector<ir::Interval>> params(first.shape->params.size());
                for (size_t k = 0; k < params.size(); ++k)
                    for (double v : values[k]) params[k].push_back({v, v});
                params[size_t(first.query)].assign(3, {});
                // The members' widest object rows per axis, smallest scale, and whether every map keeps shapes.
                std::array<double, 3> row{0, 0, 0};
                double scale = INFINITY;
                bool conformal = true;
                for (size_t mi : members) {
                    const InstancePlan& p = plan(mi);
                    std::array<double, 3> r;
                    for (size_t a = 0; a < 3; ++a) {
                        r[a] = std::hypot(p.inv_linear[a * 3], p.inv_linear[a * 3 + 1], p.inv_linear[a * 3 + 2]);
                        row[a] = std::max(row[a], r[a]);
                    }
                    const double lo = std::min({r[0], r[1], r[2]}), hi = std::max({r[0], r[1], r[2]});
                    double cross = 0;  // rows of a rotation times a scale are orthogonal
                    for (size_t a = 0; a < 3; ++a)
                        for (size_t b = a + 1; b < 3; ++b)
                            cross = std::max(cross, std::fabs(p.inv_linear[a * 3] * p.inv_linear[b * 3] + p.inv_linear[a * 3 + 1] * p.inv_linear[b * 3 + 1] +
                                                              p.inv_linear[a * 3 + 2] * p.inv_linear[b * 3 + 2]));
                    conformal &= hi <= 1.01 * lo && cross <= 0.01 * hi * hi;
                    scale = std::min(scale, p.scale);
                }
                if (!(scale > 0) || !std::isfinite(scale)) continue;
                const int fn = lower_module_cached(*first.shape, ctx_);
                const double level = o_.thickness_level / scale;
                auto box = ir::support_box(m_, fn, first.query, params, level, 48, 16, kWork);
                if (!box) continue;
                double thickness = INFINITY;
                for (size_t a = 0; a < 3; ++a)
                    if (row[a] > 0) thickness = std::min(thickness, (box->hi[a] - box->lo[a]) / row[a]);
                if (conformal)
                    if (auto depth = ir::deepest_bound(m_, fn, first.query, params, box->lo, box->hi, 16, kWork))
                        thickness = std::min(thickness, 2 * (*depth * scale + o_.thickness_level));
                // A relative tolerance: the band is the tolerance times the distance from the camera to the nearest
                // member's box (its world centre, less its half-diagonal through the object → world map), not 1.
                if (o_.thickness_eye && std::isfinite(thickness)) {
                    double nearest = INFINITY, half = 0;
                    std::array<double, 3> centre;
                    for (size_t a = 0; a < 3; ++a) {
                        centre[a] = 0.5 * (box->lo[a] + box->hi[a]);
                        half += std::pow(0.5 * (box->hi[a] - box->lo[a]), 2);
                    }
                    half = std::sqrt(half);
                    for (size_t mi : members) {
                        const InstancePlan& p = plan(mi);
                        bool singular = false;
                        std::vector<double> Li = ir::mat_inverse(p.inv_linear, 3, &singular);
                        if (singular || !std::isfinite(half)) {
                            nearest = 0;
                            break;
                        }
                        double frobenius = 0, d2 = 0;
                        for (double x : Li) frobenius += x * x;
                        for (size_t r = 0; r < 3; ++r) {
                            double w = 0;
                            for (size_t c = 0; c < 3; ++c) w += Li[r * 3 + c] * (centre[c] - p.inv_offset[c]);
                            d2 += std::pow(w - (*o_.thickness_eye)[r], 2);
                        }
                        nearest = std::min(nearest, std::max(std::sqrt(d2) - half * std::sqrt(frobenius), 0.0));
                    }
                    const double band = o_.thickness_level * std::max(nearest, 1e-3);
                    if (band > o_.thickness_level) thickness += 2 * (band - o_.thickness_level);
                }
                const InstancePlan& named = plan(members[0]);
                if (std::isfinite(thickness) && thickness > 0 && (!out_.thinnest || thickness < out_.thinnest->thickness))
                    out_.thinnest = ThinPart{thickness, named.name, named.desc->type_span};
            }
    }
    bool runtime_transform(const InstancePlan& p) const {
        return p.has_transform && (p.transform_uses_inputs || (!o_.params_constant && !p.transform->params.empty()));
    }

    // ---- items ----

    static Item single(size_t plan) {
        Item it;
        it.members = {plan};
        return it;
    }

    // Whether instances of one shape and material can be a group as far as their sequence parameters (x_i ∈ ℝ³:
    // an array per instance) go: a group's per-member table of them would be an array of arrays, which GLSL ES
    // has not (a trial's four instances of a shape with a sequence: invalid IR, exit 3, and --meta read past the
    // sequence). They group where the sequences are constants equal in every member (one shared array).
    bool sequences_shared(const std::vector<size_t>& members) const {
        const InstancePlan& a = plan(members[0]);
        auto same = [&](const CheckedModule* mod, const std::vector<std::vector<double>> InstancePlan::*values) {
            if (!mod) return true;
            for (size_t k = 0; k < mod->params.size(); ++k) {
                if (!mod->params[k].type.is_array()) continue;
                if (!o_.params_constant) return false;
                for (size_t mi : members)
                    if ((plan(mi).*values)[k] != (a.*values)[k]) return false;
            }
            return true;
        };
        return same(a.shape, &InstancePlan::shape_values) && same(a.material, &InstancePlan::material_values);
    }

    void make_items() {
        // Instances that can share code: one shape, one material, a transform known at compile time, `bound`
        // or not. In order of first appearance; members keep their order.
        std::map<std::tuple<const CheckedModule*, const CheckedModule*, bool>, std::vector<size_t>> kinds;
        std::vector<std::tuple<const CheckedModule*, const CheckedModule*, bool>> order;
        for (size_t i = 0; i < plans_.size(); ++i) {
            const InstancePlan& p = plan(i);
            out_.headers[p.name] = p.desc->type + (p.material ? " with " + p.desc->material : std::string());
            if (o_.per_instance || runtime_transform(p) || p.blend >= 0) {
                items_.push_back(single(i));
                continue;
            }
            auto key = std::make_tuple(p.shape, p.material, p.desc->bound > 0);
            if (!kinds.count(key)) order.push_back(key);
            kinds[key].push_back(i);
        }
        for (const auto& key : order) {
            const auto& members = kinds[key];
            if (int(members.size()) < o_.min_group || !sequences_shared(members)) {
                for (size_t i : members) items_.push_back(single(i));
                continue;
            }
            Item g;
            g.members = members;
            g.group = true;
            std::string shape = plan(members[0]).desc->type, material = plan(members[0]).desc->material;
            g.name = unique_name(material.empty() ? shape : shape + "_" + material);
            bool bounded = std::get<2>(key);
            // (On Shadertoy past kMaxTreeInCode members only for a lattice, which needs no tables.)
            if (!bounded && members.size() >= kMinTree &&
                (!o_.params_constant || members.size() <= kMaxTreeInCode || centres_form_lattice(members)) && !o_.per_instance) {
                // No `bound` written: the compiler derives one from the shape where it can (ir/Support.h).
                if (auto R = derived_bound(members)) {
                    for (size_t mi : members) derived_bound_[mi] = *R;
                    bounded = true;
                    out_.group_notes.push_back(fmt::format("{}: `bound = {}` derived from the shape", shape, fmt::format("{:.4g}", *R)));
                } else if (auto H = !o_.params_constant && members.size() <= kMaxHullMembers ? derived_bound(members, true)
                                                                                               : std::optional<double>{}) {
                    // Over the hull of the members' values (Shadertoy's), guarded at run time: while any member's
                    // values leave it, the hierarchy enters every node and no sphere stands in (48 bumpy balls on
                    // WebGL2 evaluated all 48 at every step: a frame 9× Shadertoy's; trial77).
                    for (size_t mi : members) derived_bound_[mi] = *H, hull_bound_[mi] = 1;
                    bounded = true;
                    g.hull_valid = add_prepared(g.name + "_within_hull", Type::scalar(),
                                                "1 while every member's sliders are within the hull of their values (its bounding spheres hold)");
                    out_.group_notes.push_back(fmt::format("{}: `bound = {}` derived from the shape while its members' sliders are within "
                                                           "the hull of their values", shape, fmt::format("{:.4g}", *H)));
                } else if (!o_.params_constant) {
                    // On a target with sliders the bound must hold over the sliders' whole ranges, which are often far
                    // wider than the members' spacing (a sphere's radius up to 3 on a grid of 1): then every step
                    // evaluates every member, where Shadertoy's constants give a hierarchy (a new user's trial: 1,000
                    // spheres, 865 shape evaluations per scene evaluation on webgl2 against 1.5). Said, not silent.
                    out_.warnings.push_back(
                        {plan(members[0]).desc->type_span,
                         fmt::format("{} instances of '{}' without `bound` are all evaluated at every step on this target: the "
                                     "bounding sphere iqc derives from the shape over its sliders' ranges{} is unbounded or wider "
                                     "than their spacing; give them `bound = R` (a radius that holds for the slider values you "
                                     "use) for a bounding-volume hierarchy",
                                     members.size(), shape,
                                     members.size() <= kMaxHullMembers ? ", and over its members' values alone," : "")});
                }
            }
            g.derived_bound = bounded && !std::get<2>(key);
            if (bounded && members.size() >= kMinTree && g.hull_valid < 0) find_lattice(g);
            if (bounded && members.size() >= kMinTree && (!o_.params_constant || members.size() <= kMaxTreeInCode)) build_tree(g);
            else if (std::get<2>(key) && members.size() > kMaxTreeInCode && !g.lattice.found())
                out_.warnings.push_back({plan(members[0]).desc->type_span,
                                         fmt::format("{} instances of '{}' with `bound` are marched in one loop, without a bounding-volume "
                                                     "hierarchy: on the shadertoy target its tables would be code, and past {} members "
                                                     "llvmpipe compiles them for minutes; --target webgl2 keeps them in a texture "
                                                     "and builds the hierarchy",
                                                     members.size(), shape, kMaxTreeInCode)});
            out_.group_notes.push_back(fmt::format("{}{}: {} instances in one loop", shape, material.empty() ? "" : " with " + material,
                                                   members.size()));
            items_.push_back(std::move(g));
        }
        // Ids: items in the order made (groups after the single instances of their kind would break the
        // user's order for ties only; the ids are the renderer's business).
        int id = 0;
        for (Item& it : items_) {
            it.id = id;
            id += int(it.members.size());
            if (!it.group) it.name = plan(it.members[0]).name;
        }
        // Blends (not in I♥IQ's per-instance architecture, whose march takes each instance alone).
        if (!o_.per_instance) {
            blend_items_.assign(s_.blends.size(), {});
            for (size_t i = 0; i < items_.size(); ++i)
                if (!items_[i].group && plan(items_[i].members[0]).blend >= 0) {
                    items_[i].blend = plan(items_[i].members[0]).blend;
                    blend_items_[size_t(items_[i].blend)].push_back(i);
                }
        }
    }

    // A blend's distance at p and each member's weight: the members' distances folded by Quilez's polynomial
    // smooth minimum ("smooth minimum", 2013): h = clamp(1/2 + (d_i − d)/(2k), 0, 1), d ← mix(d_i, d, h) −
    // k·h·(1 − h), the weights so far times h and the new member's 1 − h. Its gradient is h∇d + (1 − h)∇d_i, a
    // convex combination: 1-Lipschitz members give a 1-Lipschitz blend. `counted`: the members' distance
    // functions return (d, shapes evaluated) and so does this (a vec2); `weights`: filled when given.
    ValueId blend_distance(Builder& b, int blend, ValueId p, bool bounded, bool counted, std::vector<ValueId>* weights) {
        const auto& members = blend_items_[size_t(blend)];
        ValueId k = b.scalar(s_.blends[size_t(blend)].radius);
        ValueId d = ValueId(-1), count = ValueId(-1), K = ValueId(-1);
        std::vector<ValueId> hs;  // member m's h at hs[m - 1]
        for (size_t m = 0; m < members.size(); ++m) {
            Item& it = items_[members[m]];
            ValueId call = b.call(bounded ? it.distance_fn : it.unbounded_fn, {p});
            ValueId di = counted ? b.op(Op::Extract, {call}, 0) : call;
            // The member's own distance, not its distance divided by its Lipschitz factor: the blend of d/K over a
            // radius r is the blend of d over K·r (a trial's: two balls 0.4 apart merged under `# lipschitz: 4` and
            // stayed apart under 1; a point cloud's K, 1 on Shadertoy and 12 on webgl2, changed its blend's shape).
            // The blend is divided by the members' largest factor (its gradient is a convex combination of theirs).
            const ValueId Ki = b.global(lipschitz_factor(it));
            di = b.op(Op::Mul, {b.named(di, it.name), Ki});
            K = K == ValueId(-1) ? Ki : b.builtin("max", {K, Ki});
            if (counted) {
                ValueId c = b.op(Op::Extract, {call}, 1);
                count = count == ValueId(-1) ? c : b.op(Op::Add, {count, c});
            }
            if (m == 0) {
                d = di;
                continue;
            }
            ValueId h = b.builtin("clamp", {b.op(Op::Add, {b.scalar(0.5), b.op(Op::Div, {b.op(Op::Sub, {di, d}), b.op(Op::Mul, {b.scalar(2), k})})}),
                                            b.scalar(0), b.scalar(1)});
            h = b.named(h, "h");
            ValueId one_minus = b.op(Op::Sub, {b.scalar(1), h});
            d = b.op(Op::Sub, {b.builtin("mix", {di, d, h}), b.op(Op::Mul, {b.op(Op::Mul, {k, h}), one_minus})});
            hs.push_back(h);
        }
        if (weights) {
            // Member i's weight: (1 − h_i)·h_(i+1)·…·h_(n−1) (the first's: every h), as running products from the
            // last member back: linear in the members.
            weights->assign(members.size(), ValueId(-1));
            ValueId suffix = ValueId(-1);
            for (size_t m = members.size(); m-- > 1;) {
                ValueId one_minus = b.op(Op::Sub, {b.scalar(1), hs[m - 1]});
                (*weights)[m] = suffix == ValueId(-1) ? one_minus : b.op(Op::Mul, {one_minus, suffix});
                suffix = suffix == ValueId(-1) ? hs[m - 1] : b.op(Op::Mul, {hs[m - 1], suffix});
            }
            (*weights)[0] = suffix;
        }
        d = b.op(Op::Div, {b.named(d, "blend"), K});
        return counted ? b.construct(Type::vector(2), {d, count}) : d;
    }

    // The group's bounding-volume hierarchy from its members' `bound` spheres in world space. On Shadertoy, without a
    // lattice (which finds a member from its cell, in the members' order), the members take the hierarchy's leaf order: their ids and
    // per-member tables follow it (the ids are the renderer's; per-member parameters keep their instances' names),
    // so a leaf's members are a run of the tables, read without a table of the leaf order between. That table was
    // a third of the code tables of 1,000 tilted rings, and llvmpipe's compile grows with the square of the code
    // tables' elements (Mesa's copy propagation of their initialisers): 1.31-2.35 s -> 0.66-1.46 s, and a frame
    // 15% faster (one dependent lookup less per member; bench/rings.sh 1000 irregular, shadertoy, stop 42).
    // With a lattice the hierarchy (for the unbounded scene) lists the members through Item::tree_order.
    void build_tree(Item& g) {
        std::vector<BoundingSphere> spheres;
        for (size_t mi : g.members) spheres.push_back(world_sphere(plan(mi).inv_linear, plan(mi).inv_offset, bound_of(mi)));
        g.tree = build_bounds_tree(spheres, kTreeBranching);
        g.exact = plan(g.members[0]).shape->exactness == "exact";
        // Only where the tables are constants in the code (Shadertoy): on targets with sliders the html page keeps
        // slider values by block member or texture offset across `iqc serve`'s reloads, and an edit that moves one
        // instance would renumber others (a new user's trial: 42 of 906 saved values on other instances); there
        // the tables are uniform blocks or the texture, whose size costs no compile, and --meta lists the
        // instances in the scene's order.
        if (o_.params_constant && !g.lattice.found()) {
            std::vector<size_t> leaf_order;
            for (int k : g.tree.order) leaf_order.push_back(g.members[size_t(k)]);
            g.members = std::move(leaf_order);
            for (size_t k = 0; k < g.tree.order.size(); ++k) g.tree.order[k] = int(k);
            g.leaf_ordered = true;
        }
    }

    // Whether a lattice group's members sit on their cells' centres to float precision.
    static bool on_cell_centres(const Item& g) {
        double scale = 1;
        for (size_t c = 0; c < 3; ++c) scale = std::max({scale, std::fabs(g.lattice.origin[c]), g.lattice.spacing[c] * g.lattice.n[c]});
        return g.lattice.deviation <= 1e-7 * scale;
    }

    // Whether a lattice's members differ only in their place: one linear map, scale, bound and shape parameter
    // values (known at compile time, or one shared global). Then member k at p is member `base` at
    // p − (cell_k − cell_base)·spacing, whose data are constants: no per-member arithmetic on k (the tables pass's
    // k % 10, k / 100, … are integer divisions, which SIMD CPUs scalarise).
    bool members_alike(const Item& g) {
        const size_t a = g.members[0];
        // Evaluated at the lattice's offsets, not their own: only where these are theirs (to float precision).
        if (!on_cell_centres(g)) return false;
        for (size_t mi : g.members)
            if (plan(mi).inv_linear != plan(a).inv_linear || plan(mi).scale != plan(a).scale || bound_of(mi) != bound_of(a) ||
                plan(mi).shape_values != plan(a).shape_values)
                return false;
        // Parameters the renderer sets per member (sliders on webgl2) may differ at run time.
        if (!o_.params_constant)
            for (const Field& f : g.shape_params)
                if (f.global >= 0 && f.array) return false;
        return true;
    }

    // Whether a lattice group's members, not alike (members_alike), sit on their cells' centres to float precision:
    // member k's object point is then L_k·(p − centre of its cell), the centre computed from the cell (Item::centred_fn).
    bool lattice_centred(const Item& g) {
        if (!g.lattice.found() || g.offset.global < 0 || runtime_transform(plan(g.members[0])) || members_alike(g)) return false;
        return on_cell_centres(g);
    }

    // Whether the members' origins in the world (their transforms' centres) fill a lattice (InstanceLattice).
    bool centres_form_lattice(const std::vector<size_t>& members) {
        std::vector<BoundingSphere> points;
        for (size_t mi : members) points.push_back(world_sphere(plan(mi).inv_linear, plan(mi).inv_offset, 0));
        return find_instance_lattice(points).found();
    }

    // The group's lattice, where its members' world spheres fill one (a grid of instances; see kLatticeMostRadius).
    void find_lattice(Item& g) {
        std::vector<BoundingSphere> spheres;
        for (size_t mi : g.members) spheres.push_back(world_sphere(plan(mi).inv_linear, plan(mi).inv_offset, bound_of(mi)));
        InstanceLattice L = find_instance_lattice(spheres);
        if (!L.found()) return;
        double smallest = INFINITY;
        for (size_t a = 0; a < 3; ++a)
            if (L.n[a] > 1) smallest = std::min(smallest, L.spacing[a]);
        if (L.radius <= kLatticeMostRadius * smallest) g.lattice = L;
    }

    std::string unique_name(const std::string& base) {
        std::string n = glsl::identifier(base);
        for (int k = 2; global_names_.count(n); ++k) n = fmt::format("{}_{}", glsl::identifier(base), k);
        global_names_.insert(n);
        return n;
    }

    int add_global(const std::string& name, const Type& t, Global::Kind kind, std::vector<double> value, std::string comment) {
        Global g;
        g.owner = owner_;
        g.name = unique_name(name);
        g.type = t;
        g.kind = kind;
        g.value = std::move(value);
        g.bounds.input = false;
        g.comment = std::move(comment);
        m_.globals.push_back(std::move(g));
        if (owner_span_.valid()) out_.global_spans[int(m_.globals.size() - 1)] = owner_span_;
        return int(m_.globals.size() - 1);
    }

    // A compile-time fact per member: one constant when every member has the same value.
    Field constant_field(const Item& it, const std::string& what, const Type& t, const std::vector<std::vector<double>>& values,
                         const std::string& comment) {
        bool same = true;
        for (const auto& v : values) same &= v == values[0];
        if (same || !it.group)
            return {add_global(it.name + "_" + what, t, Global::Kind::Constant, values[0], comment), false};
        std::vector<double> all;
        for (const auto& v : values) all.insert(all.end(), v.begin(), v.end());
        return {add_global(it.name + "_" + what, Type::array(t, int(values.size())), Global::Kind::Constant, std::move(all), comment),
                true};
    }

    // The members' world → object maps by entry (Item::linear_split), where they differ and at most four values
    // a member (entries equal up to sign share one) hold what differs: a scalar table for one, a table of vec2 to
    // vec4 for more; false (nothing declared) otherwise.
    bool split_linear(Item& it, const std::vector<std::vector<double>>& L) {
        if (!it.group || L.empty()) return false;
        bool same = true;
        for (const auto& v : L) same &= v == L[0];
        if (same) return false;
        struct Table {
            std::vector<double> values;
            int global = -1;
        };
        std::vector<Table> tables;
        std::array<int, 9> which{};
        for (size_t e = 0; e < 9; ++e) {
            std::vector<double> v, neg;
            for (const auto& m : L) {
                v.push_back(m[e]);
                neg.push_back(-m[e]);
            }
            which[e] = -1;
            it.linear_value[e] = v[0];
            it.linear_sign[e] = 1;
            if (std::all_of(v.begin(), v.end(), [&](double x) { return x == v[0]; })) continue;
            // Equal to 1e-12 (an inverse's entries that are equal in exact arithmetic differ in their last bits;
            // far below float precision).
            auto equal = [](const std::vector<double>& a, const std::vector<double>& b) {
                for (size_t i = 0; i < a.size(); ++i)
                    if (!(std::fabs(a[i] - b[i]) <= 1e-12 * std::max(1.0, std::fabs(a[i])))) return false;
                return true;
            };
            for (size_t t = 0; t < tables.size() && which[e] < 0; ++t) {
                if (equal(tables[t].values, v)) which[e] = int(t);
                else if (equal(tables[t].values, neg)) which[e] = int(t), it.linear_sign[e] = -1;
            }
            if (which[e] < 0) {
                which[e] = int(tables.size());
                tables.push_back({v, -1});
            }
        }
        if (tables.size() > 4) return false;
        static const char* names[] = {"11", "12", "13", "21", "22", "23", "31", "32", "33"};
        static const char* xyzw = "xyzw";
        if (tables.size() == 1) {
            // One table: a scalar array named by its first entry.
            size_t first = 0;
            while (which[first] < 0) ++first;
            int g = add_global(it.name + "_to_object_" + names[first], Type::array(Type::scalar(), int(tables[0].values.size())),
                               Global::Kind::Constant, tables[0].values,
                               fmt::format("entry ({}, {}) of the world → object map, per instance (the other entries are "
                                           "constants or share this table)", first / 3 + 1, first % 3 + 1));
            for (size_t e = 0; e < 9; ++e) it.linear_global[e] = which[e] < 0 ? -1 : g, it.linear_component[e] = -1;
        } else {
            // Two to four tables: one array of vectors, member k's entries in element k's components, read by one
            // lookup a member. Scalar tables cost one lookup each, and llvmpipe's compile pays per lookup of a
            // constant array by a computed index, not by its length (100 tilted tori: two float[100] tables
            // compiled in 80.6 ms, one vec2[100] in 77.3 ms, the median of 11 interleaved runs; the
            // hand-written reference, with one vec2[7], 68.3 ms).
            const size_t n = tables.size(), members = tables[0].values.size();
            std::vector<double> packed;
            packed.reserve(n * members);
            for (size_t m = 0; m < members; ++m)
                for (const Table& t : tables) packed.push_back(t.values[m]);
            std::string what;
            for (size_t t = 0; t < n; ++t) {
                std::string entries;
                for (size_t e = 0; e < 9; ++e)
                    if (which[e] == int(t))
                        entries += fmt::format("{}{}({}, {})", entries.empty() ? "" : ", ", it.linear_sign[e] < 0 ? "−" : "", e / 3 + 1, e % 3 + 1);
                what += fmt::format("{}.{}: {}", t ? "; " : "", xyzw[t], entries);
            }
            int g = add_global(it.name + "_to_object", Type::array(Type::vector(int(n)), int(members)), Global::Kind::Constant,
                               std::move(packed),
                               fmt::format("the entries of the world → object map that differ, per instance ({}; the others "
                                           "are constants)", what));
            for (size_t e = 0; e < 9; ++e) it.linear_global[e] = which[e] < 0 ? -1 : g, it.linear_component[e] = which[e];
        }
        it.linear_split = true;
        return true;
    }

    // A module parameter of every member: a slider per instance, shared (one constant) when parameters are
    // constants and every member has the same value.
    Field parameter_field(const Item& it, const CheckedModule& mod, const char* role, size_t k,
                          const std::vector<std::vector<double>>& values) {
        const ParamInfo& pi = mod.params[k];
        bool same = true;
        for (const auto& v : values) same &= v == values[0];
        bool shared = it.group && same && o_.params_constant;
        Global g;
        std::string base = it.group ? fmt::format("{}_{}_{}", mod.ast.name, role, pi.name) : fmt::format("{}_{}_{}", it.name, role, pi.name);
        g.name = unique_name(base);
        g.kind = Global::Kind::Parameter;
        g.type = (it.group && !shared) ? Type::array(pi.type, int(values.size())) : pi.type;
        g.per_member = it.group && !shared;
        for (const auto& v : (it.group && !shared) ? values : std::vector<std::vector<double>>{values[0]})
            g.value.insert(g.value.end(), v.begin(), v.end());
        g.bounds.input = false;
        if (pi.bounded) {
            // Widened to hold each member's value: an override outside the module's bounds (warned) is the slider's
            // start, which the analyses (ranges, Lipschitz bounds) must cover and an HTML slider must be able to show
            // (a trial's r = 0.9 over [0.05, 0.5]: the page's slider stopped at 0.5, --meta said bounds [0.05, 0.5]).
            g.bounds.lo = pi.lo;
            g.bounds.hi = pi.hi;
            const size_t n = g.bounds.lo.size();
            for (const auto& v : values)
                for (size_t c = 0; c < v.size() && n > 0 && g.bounds.hi.size() == n; ++c) {
                    if (!std::isfinite(v[c])) continue;
                    g.bounds.lo[c % n] = std::min(g.bounds.lo[c % n], v[c]);
                    g.bounds.hi[c % n] = std::max(g.bounds.hi[c % n], v[c]);
                }
        }
        g.comment = param_comment(pi);
        g.owner = owner_;
        for (size_t mi : it.members) g.params.push_back({plan(mi).name, mod.ast.name, role, pi.name, pi.description});
        m_.globals.push_back(std::move(g));
        return {int(m_.globals.size() - 1), it.group && !shared};
    }

    void declare_lights() {
        auto declare = [&](const LightDesc& l, const char* what, const char* kind, const std::array<double, 3>& v, const char* doc) {
            Global g;
            g.name = unique_name(l.name + "_" + what);
            g.kind = Global::Kind::Parameter;
            g.type = Type::vector(3);
            g.value = {v[0], v[1], v[2]};
            g.bounds.input = false;
            g.comment = fmt::format("{} ({}) {}", l.name, kind, std::string(what) == "color" ? "colour" : what);
            g.owner = l.name;
            g.params.push_back({l.name, kind, "light", what, doc});
            m_.globals.push_back(std::move(g));
            return int(m_.globals.size() - 1);
        };
        // A bounce light without a direction comes from opposite the first sun, horizontally (Quilez's outdoor
        // lighting), else from below (light bounced off the ground).
        std::array<double, 3> bounce_from{0, -1, 0};
        for (const auto& l : s_.lights)
            if (l.kind == LightKind::Sun) {
                double h = std::hypot(l.direction[0], l.direction[2]);
                if (h > 1e-6) bounce_from = {-l.direction[0] / h, 0, -l.direction[2] / h};
                break;
            }
        std::vector<std::pair<int, int>> suns;
        for (const auto& l : s_.lights) {
            switch (l.kind) {
                case LightKind::Point:
                    light_pos_.push_back(declare(l, "position", "point", l.position, "light position"));
                    light_col_.push_back(declare(l, "color", "point", l.color, "light colour"));
                    ++point_lights_;
                    break;
                case LightKind::Sun: {
                    int d = declare(l, "direction", "sun", l.direction, "direction toward the sun");
                    suns.push_back({d, declare(l, "color", "sun", l.color, "sun colour")});
                    break;
                }
                case LightKind::Sky:
                    ambient_.push_back({l.kind, declare(l, "color", "sky", l.color, "sky light colour"), -1});
                    break;
                case LightKind::Bounce: {
                    int c = declare(l, "color", "bounce", l.color, "bounce light colour");
                    ambient_.push_back({l.kind, c, declare(l, "direction", "bounce", l.has_direction ? l.direction : bounce_from,
                                                           "direction the bounce light comes from")});
                    break;
                }
            }
        }
        for (auto [d, c] : suns) {
            light_pos_.push_back(d);
            light_col_.push_back(c);
        }
    }

    // iqc_ambient_light(N) -> the indirect light reaching a surface with unit normal N: each sky light's colour
    // times (1 + N_y)/2 (a hemisphere above, fully seen by an up-facing surface), each bounce light's times
    // max(0, N·d̂) (Quilez, "outdoors lighting"). Materials bind it as `C_A`; ambient occlusion darkens it.
    int ambient_function() {
        if (ambient_fn_ >= 0) return ambient_fn_;
        ir::Function f;
        f.name = "iqc_ambient_light";
        f.glsl_name = f.name;
        f.inline_hint = true;
        Builder b(m_, f);
        ValueId N = b.param("N", Type::vector(3));
        ValueId sum = ValueId(-1);
        for (const AmbientLight& a : ambient_) {
            ValueId w;
            if (a.kind == LightKind::Sky) {
                w = b.op(Op::Add, {b.scalar(0.5), b.op(Op::Mul, {b.scalar(0.5), b.op(Op::Extract, {N}, 1)})});
            } else {
                ValueId g = b.global(a.direction);  // a unit direction (a slider may make it zero: guarded)
                ValueId d = b.op(Op::Div, {g, b.builtin("max", {b.builtin("length", {g}), b.scalar(1e-9)})});
                w = b.builtin("max", {b.scalar(0), b.op(Op::Dot, {N, d})});
            }
            ValueId term = b.op(Op::Mul, {w, b.global(a.color)});
            sum = sum == ValueId(-1) ? term : b.op(Op::Add, {sum, term});
        }
        f.result = b.named(sum, "C_A");
        m_.functions.push_back(std::move(f));
        ambient_fn_ = int(m_.functions.size() - 1);
        return ambient_fn_;
    }

    std::string owner_of(const Item& it) {
        const InstancePlan& first = plan(it.members[0]);
        return it.group ? fmt::format("{}: {} instances of {}", it.name, it.members.size(), out_.headers[first.name])
                        : fmt::format("{}: {}", it.name, out_.headers[first.name]);
    }

    void declare_item(Item& it) {
        const InstancePlan& first = plan(it.members[0]);
        owner_ = owner_of(it);
        owner_span_ = first.desc->type_span;
        std::vector<std::vector<double>> L, off, sc, R;
        for (size_t mi : it.members) {
            L.push_back(plan(mi).inv_linear);
            off.push_back(plan(mi).inv_offset);
            sc.push_back({plan(mi).scale});
            R.push_back({bound_of(mi)});
        }
        if (runtime_transform(first)) {
            declare_runtime_transform(it);
        } else {
            bool identity = true, no_offset = true, unit = true;
            for (size_t k = 0; k < L.size(); ++k) {
                identity &= is_identity3(L[k]);
                no_offset &= is_zero(off[k]);
                unit &= sc[k][0] == 1.0;
            }
            std::string what = it.group ? "world → object, per instance" : first.transform_comment;
            if (!identity && !split_linear(it, L)) it.to_object = constant_field(it, "to_object", Type::matrix(3, 3), L, what);
            if (!no_offset) it.offset = constant_field(it, "offset", Type::vector(3), off, identity ? what : "");
            if (!unit) it.scale = constant_field(it, "scale", Type::scalar(), sc, "1 / Lipschitz factor: keeps distances conservative");
        }
        if (first.desc->bound > 0 && first.blend >= 0) {
            // A blend reads its members' distances up to its radius away: a bound sphere's distance there is only
            // a lower bound and would change the blended shape (a crease where the sphere switches off).
            out_.warnings.push_back({first.desc->bound_span, fmt::format("`bound` is not used for '{}': it is part of a blend, which "
                                                                         "reads its true distance", first.name)});
        } else if (bound_of(it.members[0]) > 0) {
            it.bound = constant_field(it, "bound", Type::scalar(), R,
                                      it.derived_bound ? "radius of the bounding sphere, derived from the shape"
                                                       : "`bound`: radius of the bounding sphere");
            out_.any_bound = true;
        }
        for (size_t l = 0; l < it.tree.levels.size(); ++l) {
            const BoundsTreeLevel& L = it.tree.levels[l];
            std::vector<double> c, h, fi, co;
            for (size_t n = 0; n < L.nodes.size(); ++n) {
                c.insert(c.end(), L.nodes[n].center.begin(), L.nodes[n].center.end());
                h.insert(h.end(), L.nodes[n].half.begin(), L.nodes[n].half.end());
                fi.push_back(L.first[n]);
                co.push_back(L.count[n]);
            }
            int nodes = int(L.nodes.size());
            bool last = l + 1 == it.tree.levels.size();
            std::string lv = fmt::format("level {} of {}", l + 1, it.tree.levels.size());
            auto table = [&](const char* what, const Type& t, std::vector<double> v, std::string comment) {
                return Field{add_global(fmt::format("{}_tree{}_{}", it.name, l, what), Type::array(t, nodes), Global::Kind::Constant,
                                        std::move(v), std::move(comment)),
                             true};
            };
            it.tree_globals.push_back({table("center", Type::vector(3), std::move(c), "bounding-box hierarchy, " + lv + ": node centres"),
                                       table("half", Type::vector(3), std::move(h), "node half-extents"),
                                       table("first", Type::integer(), std::move(fi), last ? "first member" : "first child node"),
                                       table("count", Type::integer(), std::move(co), last ? "members" : "child nodes")});
        }
        if (!it.tree.levels.empty() && !it.leaf_ordered) {
            std::vector<double> order(it.tree.order.begin(), it.tree.order.end());
            const Type t = Type::array(Type::integer(), int(order.size()));
            it.tree_order = {add_global(it.name + "_tree_members", t, Global::Kind::Constant,
                                        std::move(order), "bounding-volume hierarchy: the members in leaf order"),
                             true};
        }
        auto params = [&](const CheckedModule& mod, const char* role, const std::vector<int>& skip,
                          const std::vector<std::vector<double>> InstancePlan::*values, std::vector<Field>& fields) {
            fields.assign(mod.params.size(), {});
            for (size_t k = 0; k < mod.params.size(); ++k) {
                if (std::find(skip.begin(), skip.end(), int(k)) != skip.end()) continue;
                if (&mod == first.material && first.lit_by(int(k), bind_lights_, ambient_lights_)) continue;
                if (&mod == first.material && first.binds_footprint() && int(k) == mod.find_param(kFootprint)) continue;
                std::vector<std::vector<double>> vals;
                for (size_t mi : it.members) vals.push_back((plan(mi).*values)[k]);
                fields[k] = parameter_field(it, mod, role, k, vals);
            }
        };
        params(*first.shape, "shape", {first.query}, &InstancePlan::shape_values, it.shape_params);
        if (first.material) params(*first.material, "material", first.material->roles, &InstancePlan::material_values, it.material_params);
    }

    // A transform with sliders (uniform targets) or time: its parameters are globals, and iqc_prepare
    // inverts it once per pixel into prepared globals.
    void declare_runtime_transform(Item& it) {
        const InstancePlan& p = plan(it.members[0]);
        const CheckedModule& t = *p.transform;
        it.transform_fn = lower_module(t, p.name + ".transform", p.name + "_transform", ctx_);
        m_.functions[size_t(it.transform_fn)].param_bounds = parameter_bounds(t);
        // Inlined into iqc_prepare, its one caller: a function per instance made glslang's call-graph checks,
        // quadratic in the calls between functions, most of the compile (2,000 moving spheres: 1.2 s of 1.7).
        m_.functions[size_t(it.transform_fn)].inline_hint = true;
        for (size_t k = 0; k < t.params.size(); ++k) {
            std::vector<std::vector<double>> vals = {t.params[k].value};
            it.transform_params.push_back(parameter_field(it, t, "transform", k, vals));
            m_.globals.back().params.back().module = "transform";
        }
        it.to_object = {add_prepared(it.name + "_to_object", Type::matrix(3, 3), p.transform_comment + " (per pixel)"), false};
        it.offset = {add_prepared(it.name + "_offset", Type::vector(3), ""), false};
        it.scale = {add_prepared(it.name + "_scale", Type::scalar(), "1 / Lipschitz factor"), false};
        out_.has_prepare = true;
    }

    int add_prepared(const std::string& name, const Type& t, std::string comment) {
        int g = add_global(name, t, Global::Kind::Prepared, {}, std::move(comment));
        m_.globals[size_t(g)].bounds.input = true;
        return g;
    }

    // ---- reading per-instance data ----

    static ValueId read(Builder& b, const Field& f, ValueId k) {
        ValueId g = b.global(f.global);
        return f.array ? b.op(Op::Index, {g, k}) : g;
    }

    // The arguments of a module call: renderer-bound parameters from `bound`, the rest from the fields.
    std::vector<ValueId> module_args(Builder& b, const CheckedModule& mod, const std::vector<Field>& fields,
                                     const std::map<int, ValueId>& bound, ValueId k) {
        std::vector<ValueId> args;
        for (size_t i = 0; i < mod.params.size(); ++i) {
            if (auto it = bound.find(int(i)); it != bound.end()) args.push_back(it->second);
            else args.push_back(read(b, fields[i], k));
        }
        return args;
    }

    // ---- the scene distance ----

    // Whether shape function fn (with the functions it calls) is at most kCheapShape operations without a loop:
    // a bounding sphere's length, test and branch cost about as much as evaluating it.
    bool cheap_shape(int fn) const {
        constexpr int kCheapShape = 12;
        int ops = 0;
        std::function<bool(int, int)> count = [&](int g, int level) {
            if (level > 8) return false;
            for (const ir::Instr& in : m_.functions[size_t(g)].body) {
                switch (in.op) {
                    case Op::Param: case Op::Const: case Op::Global: case Op::Extract: case Op::Construct: case Op::Copy: break;
                    case Op::Loop: return false;
                    case Op::Call: if (!count(in.aux, level + 1)) return false; break;
                    default: ++ops;
                }
                if (ops > kCheapShape) return false;
            }
            return true;
        };
        return count(fn, 0);
    }

    // One item's distance at world point p: (p [, k]) -> ℝ, marked for inlining.
    // `bounded`: with the item's `bound` sphere (iqc_scene), else without it (iqc_scene_unbounded, never
    // instrumented).
    // `centred`: p is already the point moved to the member's lattice cell centre (Item::centred_fn): no offset.
    int item_distance(const Item& it, bool bounded, bool centred = false) {
        const InstancePlan& first = plan(it.members[0]);
        const bool counted = o_.instrument && bounded;
        ir::Function f;
        f.name = "iqc_distance." + it.name + (bounded ? "" : ".unbounded") + (centred ? ".centred" : "");
        f.glsl_name = it.name + (bounded ? "_distance" : "_distance_unbounded") + (centred ? "_centred" : "");
        f.inline_hint = true;
        int fn = int(m_.functions.size());
        m_.functions.push_back({});
        Builder b(m_, f);
        ValueId p = b.param("p", Type::vector(3));
        ValueId k = it.group ? b.param("k", Type::integer()) : ValueId(-1);
        ValueId q = p;
        if (it.linear_split) {
            std::vector<ValueId> e;
            ValueId row = 0;  // member k's element of a table of vectors, read once
            bool read_row = false;
            for (size_t i = 0; i < 9; ++i) {
                if (it.linear_global[i] < 0) {
                    e.push_back(b.scalar(it.linear_value[i]));
                    continue;
                }
                ValueId x;
                if (it.linear_component[i] < 0) {
                    x = b.op(Op::Index, {b.global(it.linear_global[i]), k});
                } else {
                    if (!read_row) row = b.op(Op::Index, {b.global(it.linear_global[i]), k}), read_row = true;
                    x = b.op(Op::Extract, {row}, it.linear_component[i]);
                }
                e.push_back(it.linear_sign[i] < 0 ? b.op(Op::Neg, {x}) : x);
            }
            q = b.op(Op::Mul, {b.construct(Type::matrix(3, 3), e), q});
        } else if (it.to_object.global >= 0) {
            q = b.op(Op::Mul, {read(b, it.to_object, k), q});
        }
        if (it.offset.global >= 0 && !centred) q = b.op(Op::Add, {q, read(b, it.offset, k)});
        if (q != p) f.body[q].name = "q";
        // Scaled like the shape by the transform's Lipschitz factor; the shape's own (declared, or derived by
        // the compiler) divides the result in the lipschitz pass (f.lipschitz).
        auto conservative = [&](ValueId d) {
            if (it.scale.global >= 0) d = b.op(Op::Mul, {d, read(b, it.scale, k)});
            return d;
        };
        int shape_fn = lower_module_cached(*first.shape, ctx_);
        std::vector<ValueId> args = module_args(b, *first.shape, it.shape_params, {{first.query, q}}, k);
        ValueId bound_d = 0, far = 0;
        // A bound the compiler derived (for a group's hierarchy or lattice) stands in for a cheap shape only where
        // it saves more than it costs: a torus is two lengths, and its sphere's length, test and branch per member
        // made 100 instances' frame 5% slower (the hand-written reference has none). A written `bound` always does.
        const bool stand_in = bounded && it.bound.global >= 0 && !(it.derived_bound && cheap_shape(shape_fn));
        if (stand_in) {
            // `bound = R`: outside the sphere ‖q‖ = R by more than the margin, its distance (a lower bound) stands
            // for the shape's, which is not evaluated.
            bound_d = conservative(b.op(Op::Sub, {b.builtin("length", {q}), read(b, it.bound, k)}));
            f.body[bound_d].name = "bound";
            far = b.compare(CompareKind::Gt, bound_d, b.scalar(o_.bound_margin));
            if (it.hull_valid >= 0) far = b.op(Op::And, {far, b.compare(CompareKind::Gt, b.global(it.hull_valid), b.scalar(0.5))});
        }
        ValueId d = conservative(b.call(shape_fn, std::move(args)));
        if (stand_in) d = b.if_(far, bound_d, d);
        f.result = d;
        if (counted) {  // shapes evaluated: 0 where the bound stood in
            ValueId one = b.scalar(1);
            ValueId count = stand_in ? b.op(Op::Select, {far, b.scalar(0), one}) : one;
            f.result = b.construct(Type::vector(2), {d, count});
        }
        // The variant without its bound sphere is bounded by the same factor: the same object function, whose
        // estimate the lipschitz pass computes once.
        f.lipschitz = bounded && !centred ? lipschitz_spec(it, shape_fn) : m_.functions[size_t(it.distance_fn)].lipschitz;
        m_.functions[size_t(fn)] = std::move(f);
        return fn;
    }

    // What the lipschitz pass needs: the shape's object-space distance as a function of q (and k), and the
    // box of q where it is evaluated: its bounding sphere, else the camera's reach (max_dist around it)
    // seen from the shape (for a group, the hull over its members).
    ir::LipschitzSpec lipschitz_spec(const Item& it, int shape_fn) {
        const InstancePlan& first = plan(it.members[0]);
        ir::LipschitzSpec spec;
        // `# lipschitz: 1` is a declaration too: applied as written (no derived bound replaces it), warned where
        // the gradient's samples exceed it (it was taken for no pragma, and a derived 3.5 replaced it silently).
        spec.declared = first.shape->lipschitz_declared ? first.shape->lipschitz : 0;
        spec.trusted = first.shape->exactness == "exact" || first.shape->exactness == "bound";
        spec.where = first.desc->type_span;
        spec.shape = first.shape->ast.name;
        spec.group = it.group ? int(it.members.size()) : 0;
        spec.region.input = false;
        spec.region.lo.assign(3, std::numeric_limits<double>::infinity());
        spec.region.hi.assign(3, -std::numeric_limits<double>::infinity());
        const auto& cam = s_.camera;
        double reach = s_.render.max_dist;
        for (int c = 0; c < 3; ++c) reach += std::fabs(cam.position[size_t(c)] - cam.target[size_t(c)]);  // an orbiting camera
        if (spec.group > 0 && spec.group <= 16)
            for (size_t mi : it.members) spec.member_where.push_back(plan(mi).desc->type_span);
        for (size_t mi : it.members) {
            const InstancePlan& p = plan(mi);
            if (bound_of(mi) > 0 && !hull_bound_[mi] && spec.bounds.size() < 8) {
                spec.bounds.push_back(bound_of(mi));
                spec.bound_where.push_back(plan(mi).desc->bound > 0 ? plan(mi).desc->bound_span : Span{});
            }
            for (int r = 0; r < 3; ++r) {
                double lo, hi;
                if (bound_of(mi) > 0 && !hull_bound_[mi]) {
                    double R = bound_of(mi) + 2 * o_.bound_margin / std::max(p.scale, 1e-9);
                    lo = -R, hi = R;
                    spec.ball = std::max(spec.ball, R);
                } else {  // q = L p + o for p within `reach` of the camera's target
                    lo = hi = p.inv_offset[size_t(r)];
                    for (int c = 0; c < 3; ++c) {
                        double l = p.inv_linear[size_t(r * 3 + c)], mid = cam.target[size_t(c)];
                        lo += std::min(l * (mid - reach), l * (mid + reach));
                        hi += std::max(l * (mid - reach), l * (mid + reach));
                    }
                }
                spec.region.lo[size_t(r)] = std::min(spec.region.lo[size_t(r)], lo);
                spec.region.hi[size_t(r)] = std::max(spec.region.hi[size_t(r)], hi);
            }
        }
        ir::Function o;
        o.name = "iqc_object." + it.name;
        o.glsl_name = it.name + "_object";
        Builder b(m_, o);
        ValueId q = b.param("q", Type::vector(3));
        ValueId k = it.group ? b.param("k", Type::integer()) : ValueId(-1);
        o.result = b.call(shape_fn, module_args(b, *first.shape, it.shape_params, {{first.query, q}}, k));
        m_.functions.push_back(std::move(o));
        spec.object_fn = int(m_.functions.size() - 1);
        return spec;
    }

    // iqc_scene(p) -> (distance, id[, shapes evaluated]): the union of every item, the nearest one's id.
    // `bounded`: iqc_scene; else iqc_scene_unbounded, the same union with every shape evaluated (what soft
    // shadows and ambient occlusion read: they use the distance's value, which a `bound` sphere lowers).
    void scene_function(bool bounded) {
        const bool counted = o_.instrument && bounded;
        ir::Function f;
        f.name = bounded ? ir::names::kScene : ir::names::kSceneUnbounded;
        f.glsl_name = f.name;
        f.entry = true;
        Builder b(m_, f);
        ValueId p = b.param("p", Type::vector(3));
        int width = counted ? 3 : 2;
        Type res_t = Type::vector(width);
        std::vector<double> empty = {2 * o_.max_dist, -1, 0};
        empty.resize(size_t(width));
        ValueId res = ValueId(-1);
        for (const Item& it : items_) {
            if (it.group) {
                res = group_loop(b, it, p, res == ValueId(-1) ? b.constant(res_t, empty) : res, bounded);
                continue;
            }
            ValueId call;
            if (it.blend >= 0) {  // the blend in place of its first member (its id); the other members are in it
                if (&items_[blend_items_[size_t(it.blend)][0]] != &it) continue;
                call = blend_distance(b, it.blend, p, bounded, counted, nullptr);
            } else {
                call = b.call(bounded ? it.distance_fn : it.unbounded_fn, {p});
            }
            ValueId d = counted ? b.op(Op::Extract, {call}, 0) : call;
            std::string source = plan(it.members[0]).has_transform ? plan(it.members[0]).transform_comment : "";
            d = it.blend >= 0 ? d : b.named(d, it.name, source);
            std::vector<ValueId> parts = {d, b.scalar(it.id)};
            if (counted) {
                ValueId count = b.op(Op::Extract, {call}, 1);
                parts.push_back(res == ValueId(-1) ? count : b.op(Op::Add, {b.op(Op::Extract, {res}, 2), count}));
            }
            ValueId here = b.construct(res_t, parts);
            if (res == ValueId(-1)) {
                res = b.named(here, "res");
                continue;
            }
            ValueId nearer = b.compare(CompareKind::Lt, d, b.op(Op::Extract, {res}, 0));
            if (counted) {  // the count adds up whichever is nearer
                ValueId kept = b.construct(res_t, {b.op(Op::Extract, {res}, 0), b.op(Op::Extract, {res}, 1), parts[2]});
                res = b.named(b.op(Op::Select, {nearer, here, kept}), "res");
            } else {
                res = b.named(b.op(Op::Select, {nearer, here, res}), "res");
            }
        }
        f.result = res == ValueId(-1) ? b.constant(res_t, empty) : res;
        m_.functions.push_back(std::move(f));
    }

    // iqc_lipschitz(id): the factor the lipschitz pass divides instance id's distance by, one constant per
    // item that the pass fills in. The march multiplies its distances back for the hit test (a distance
    // divided by K bounds the step, it does not say how near the surface is). An entry point only where
    // some factor exceeds 1 (the pass decides); else nothing calls it and it is not emitted.
    // The global holding item it's Lipschitz factor (made once; 1 until the lipschitz pass sets it).
    int lipschitz_factor(Item& it) {
        if (it.lipschitz_global < 0) {
            const std::string owner = owner_;
            const Span span = owner_span_;
            owner_ = owner_of(it);
            owner_span_ = plan(it.members[0]).desc->type_span;
            it.lipschitz_global = add_global(it.name + "_lipschitz", Type::scalar(), Global::Kind::Constant, {1},
                                             "the Lipschitz factor dividing its distance (the hit test multiplies it back)");
            m_.functions[size_t(it.distance_fn)].lipschitz.factor_global = it.lipschitz_global;
            owner_ = owner;
            owner_span_ = span;
        }
        return it.lipschitz_global;
    }

    void lipschitz_function() {
        ir::Function f;
        f.name = ir::names::kLipschitz;
        f.glsl_name = f.name;
        Builder b(m_, f);
        ValueId id = b.param("id", Type::integer());
        std::vector<std::tuple<long long, long long, ValueId>> cs;
        for (Item& it : items_) {
            ValueId K = b.global(lipschitz_factor(it));
            // Its variants' too (without the bound sphere, centred on a lattice's cells): where the factor follows the
            // sliders (a prepared global), each divides by it. The variant without the sphere, which soft shadows
            // march, was divided by the K of the sliders' whole ranges while the hit test and the shadows' values
            // multiplied by the cell's, and penumbrae darkened (a bounded displaced sphere on WebGL2: 18.6 dB from
            // Shadertoy's picture).
            for (int fn : {it.unbounded_fn, it.centred_fn})
                if (fn >= 0) m_.functions[size_t(fn)].lipschitz.factor_global = it.lipschitz_global;
            // A blend's distance is divided by its members' largest factor (blend_distance): its hit test multiplies that back.
            if (it.blend >= 0 && &items_[blend_items_[size_t(it.blend)][0]] == &it)
                for (size_t mi : blend_items_[size_t(it.blend)])
                    if (&items_[mi] != &it) K = b.builtin("max", {K, b.global(lipschitz_factor(items_[mi]))});
            cs.push_back({it.id, it.id + (long long)it.members.size(), K});
        }
        f.result = b.switch_(id, b.scalar(1), std::move(cs));
        m_.functions.push_back(std::move(f));
    }

    // A Loop in `outer` running the body `fill` builds for k = 0..hi over `states` (ℝ each: the nearest
    // distance, its id[, shapes evaluated]), with `captures` (name, value) read inside; returns the final
    // states. fill(b, k, states, captures) returns the next states.
    template <class Fill>
    std::vector<ValueId> counted_loop(Builder& outer, const std::string& name, ValueId hi, const std::vector<ValueId>& states,
                                      const std::vector<std::pair<std::string, ValueId>>& captures, const std::string& source,
                                      Fill fill) {
        static const char* kStates[] = {"d", "id", "shapes"};
        ir::Function body;
        body.name = name;
        body.glsl_name = name;
        std::vector<ValueId> in_states, in_captures;
        {
            Builder b(m_, body);
            ValueId k = b.param("k", Type::integer());
            for (size_t j = 0; j < states.size(); ++j) in_states.push_back(b.param(kStates[j], Type::scalar()));
            for (const auto& [cname, v] : captures) in_captures.push_back(b.param(cname, outer.function().body[v].type));
            std::vector<ValueId> next = fill(b, k, in_states, in_captures);
            for (size_t j = 0; j < next.size(); ++j) body.outputs.push_back({kStates[j], next[j]});
            body.result = body.outputs[0].second;
        }
        int fn = int(m_.functions.size());
        m_.functions.push_back(std::move(body));
        std::vector<ValueId> args = {hi};
        args.insert(args.end(), states.begin(), states.end());
        for (const auto& c : captures) args.push_back(c.second);
        ir::Instr loop;
        loop.op = Op::Loop;
        loop.type = Type::tuple(int(states.size()));
        loop.args = std::move(args);
        loop.aux = fn;
        loop.data = {0};
        loop.source = source;
        ValueId lv = outer.function().add(std::move(loop));
        std::vector<ValueId> out;
        for (size_t c = 0; c < states.size(); ++c) {
            ir::Instr mem;
            mem.op = Op::Member;
            mem.type = Type::scalar();
            mem.args = {lv};
            mem.aux = int(c);
            out.push_back(outer.function().add(std::move(mem)));
        }
        return out;
    }

    // The members of a group at [base, base + hi] of its hierarchy's leaf order, or (base -1) 0..hi, the
    // nearest kept.
    std::vector<ValueId> member_loop(Builder& outer, const Item& it, ValueId p, ValueId base, ValueId hi, const std::vector<ValueId>& states,
                                     bool bounded, const std::string& source) {
        std::vector<std::pair<std::string, ValueId>> captures = {{"p", p}};
        if (base != ValueId(-1)) captures.push_back({"first", base});
        std::string name = (bounded ? "iqc_scene." : "iqc_scene_unbounded.") + it.name + (base != ValueId(-1) ? ".members" : "");
        return counted_loop(outer, name, hi, states, captures, source, [&](Builder& b, ValueId k, const std::vector<ValueId>& st,
                                                                            const std::vector<ValueId>& cap) {
            ValueId m = k;
            if (cap.size() > 1) {
                m = b.op(Op::Add, {cap[1], k});
                if (!it.leaf_ordered) m = read(b, it.tree_order, m);
            }
            return member_step(b, it, cap[0], m, st, bounded);
        });
    }

    // Member m (ℤ) of a group evaluated at p: the states (nearest distance, its id[, shapes evaluated]) with it.
    // `at` (with `as`): evaluate member `as` at the point `at` instead (a lattice's members alike but for their
    // place: member m at p is member `as` at p moved by their offset), m still the id.
    std::vector<ValueId> member_step(Builder& b, const Item& it, ValueId p, ValueId m, const std::vector<ValueId>& st, bool bounded,
                                     ValueId at = ValueId(-1), ValueId as = ValueId(-1), int fn = -1) {
        const bool counted = o_.instrument && bounded;
        if (fn < 0) fn = bounded ? it.distance_fn : it.unbounded_fn;
        ValueId call = b.call(fn, {at != ValueId(-1) ? at : p, as != ValueId(-1) ? as : m});
        ValueId d = counted ? b.op(Op::Extract, {call}, 0) : call;
        d = b.named(d, it.name, fmt::format("instance {} + k of {}", it.id, it.members.size()));
        ValueId nearer = b.compare(CompareKind::Lt, d, st[0]);
        std::vector<ValueId> next = {b.op(Op::Select, {nearer, d, st[0]}),
                                     b.op(Op::Select, {nearer, b.op(Op::Add, {b.integer(it.id), m}), st[1]})};
        if (counted) next.push_back(b.op(Op::Add, {st[2], b.op(Op::Extract, {call}, 1)}));
        return next;
    }

    // p (ℝ³) moved to lattice cell `cell`'s centre (ℝ³, whole numbers): (p − origin) − cell·spacing, the point at
    // which a member on its cell's centre is evaluated (Item::centred_fn), in iqc_scene and in iqc_distance_of.
    ValueId to_cell_centre(Builder& b, const InstanceLattice& L, ValueId p, ValueId cell) {
        auto vec = [&](const std::array<double, 3>& a) { return b.constant(Type::vector(3), {a[0], a[1], a[2]}); };
        return b.op(Op::Sub, {b.op(Op::Sub, {p, vec(L.origin)}), b.op(Op::Hadamard, {cell, vec(L.spacing)})});
    }

    // A group over a lattice (InstanceLattice) in iqc_scene. Farther than a quarter cell from the box of its spheres, that
    // box's distance stands in for every member (a lower bound, id -1: no hit test accepts it, as with the
    // hierarchy's boxes). Nearer, the member of the nearest cell is evaluated first, then every other member whose
    // cell centre lies, per axis, within the nearest distance so far plus the spheres' radius: the others'
    // spheres are no nearer than that distance, so their distances cannot lower it (Hart 1996 §4), and the
    // result is the loop over all members' (for distances no smaller than their sphere's) or a lower bound of it.
    std::vector<ValueId> lattice_lookup(Builder& b, const Item& it, ValueId p, const std::vector<ValueId>& st) {
        const InstanceLattice& L = it.lattice;
        const Type v3 = Type::vector(3);
        auto vec = [&](const std::array<double, 3>& a) { return b.constant(v3, {a[0], a[1], a[2]}); };
        auto vec3c = [&](Builder& lb, const std::array<double, 3>& a) { return lb.constant(v3, {a[0], a[1], a[2]}); };
        auto splat = [&](ValueId x) { return b.construct(v3, {x, x, x}); };
        std::array<double, 3> inv, last, centre, half;
        // The stand-in serves farther than a quarter of the largest spacing (and the margin) from the box: nearer,
        // the lookup's exact minimum saves more steps than it costs (1,000 rings, llvmpipe: 8.8 ms a frame at a
        // quarter against 9.2 at a whole spacing and 11.5 at three).
        double far_from = o_.bound_margin, scale = 0;
        for (size_t a = 0; a < 3; ++a) {
            inv[a] = 1 / L.spacing[a];
            last[a] = L.n[a] - 1;
            centre[a] = L.origin[a] + L.spacing[a] * last[a] / 2;
            half[a] = L.spacing[a] * last[a] / 2 + L.radius;
            if (L.n[a] > 1) far_from = std::max(far_from, L.spacing[a] / 4);
            scale = std::max({scale, std::fabs(centre[a]) + half[a]});
        }
        // float32 rounding of the distances and of the cell arithmetic, and the centres' distance from their cells':
        // a little more reach.
        const double slack = 1e-5 * scale + 1e-6 + 2 * L.deviation;
        for (double& h : half) h += slack;
        const Type vt = Type::vector(int(st.size()));
        ValueId box = b.builtin("length", {b.builtin("max", {b.op(Op::Sub, {b.builtin("abs", {b.op(Op::Sub, {p, vec(centre)})}), vec(half)}),
                                                             vec({0, 0, 0})})});
        box = b.named(box, "lattice", "distance to the box of the lattice's bounding spheres");
        std::vector<ValueId> stand_in = {box, b.scalar(-1)};
        if (st.size() > 2) stand_in.push_back(st[2]);
        // (Builder calls as arguments of one call run in an order C++ leaves open: named first, the IR is the same
        // with every compiler.)
        const ValueId nearer_box = b.compare(CompareKind::Lt, box, st[0]);
        const ValueId boxed = b.construct(vt, stand_in);
        const ValueId kept = b.construct(vt, st);
        ValueId far = b.if_(nearer_box, boxed, kept);
        // The nearest cell and its member.
        ValueId u = b.op(Op::Hadamard, {b.op(Op::Sub, {p, vec(L.origin)}), vec(inv)});
        ValueId c0 = b.builtin("clamp", {b.builtin("floor", {b.op(Op::Add, {u, vec({0.5, 0.5, 0.5})})}), vec({0, 0, 0}), vec(last)});
        ValueId kf = b.op(Op::Add, {b.scalar(double(L.base)), b.op(Op::Dot, {c0, vec({double(L.stride[0]), double(L.stride[1]), double(L.stride[2])})})});
        const ValueId nearest_cell = b.op(Op::FloorInt, {b.op(Op::Add, {kf, b.scalar(0.5)})});  // maybe empty
        ValueId k0 = nearest_cell;
        auto in_range = [&](Builder& lb, ValueId k) {
            return lb.op(Op::And, {lb.compare(CompareKind::Ge, k, lb.integer(0)), lb.compare(CompareKind::Lt, k, lb.integer(L.members))});
        };
        if (L.back_axis >= 0)  // an empty cell: the filled one behind it
            k0 = b.op(Op::Select, {in_range(b, k0), k0, b.op(Op::Sub, {k0, b.integer(L.stride[size_t(L.back_axis)])})});
        k0 = b.named(k0, "nearest", "the member of the nearest (filled) cell");
        const bool alike = members_alike(it);
        const bool centred = !alike && it.centred_fn >= 0;
        const ValueId base = b.integer(L.base);
        // Member k at p as member `base` at p − cell·spacing (members_alike).
        auto moved = [&](Builder& lb, ValueId at, ValueId cellv) { return lb.op(Op::Sub, {at, lb.op(Op::Hadamard, {cellv, vec3c(lb, L.spacing)})}); };
        // p moved to member k's cell centre, origin + cell·spacing (lattice_centred).
        auto to_centre = [&](Builder& lb, ValueId at, ValueId cellv) { return to_cell_centre(lb, L, at, cellv); };
        ValueId c0used = c0;
        if ((alike || centred) && L.back_axis >= 0) {
            std::array<double, 3> e{0, 0, 0};
            e[size_t(L.back_axis)] = 1;
            c0used = b.op(Op::Select, {in_range(b, nearest_cell), c0, b.op(Op::Sub, {c0, vec(e)})});
        }
        std::vector<ValueId> st1 = alike      ? member_step(b, it, p, k0, st, true, moved(b, p, c0used), base)
                                   : centred ? member_step(b, it, p, k0, st, true, to_centre(b, p, c0used), ValueId(-1), it.centred_fn)
                                             : member_step(b, it, p, k0, st, true);
        // The cells within reach, per axis [lo, lo + count).
        ValueId reach = splat(b.op(Op::Add, {st1[0], b.scalar(L.radius + slack)}));
        ValueId lo = b.builtin("clamp", {b.builtin("ceil", {b.op(Op::Hadamard, {b.op(Op::Sub, {b.op(Op::Sub, {p, reach}), vec(L.origin)}), vec(inv)})}),
                                         vec({0, 0, 0}), vec(last)});
        ValueId hi = b.builtin("clamp", {b.builtin("floor", {b.op(Op::Hadamard, {b.op(Op::Sub, {b.op(Op::Add, {p, reach}), vec(L.origin)}), vec(inv)})}),
                                         vec({0, 0, 0}), vec(last)});
        // span: the last cell's offset from the first (negative: no cell in reach), a loop's inclusive bound as it is.
        // An axis of one cell: its cell is 0 (lo and hi are clamped to [0, 0]), a constant for the compiler.
        std::vector<ValueId> from, span;
        for (int a = 0; a < 3; ++a) {
            if (L.n[size_t(a)] == 1) {
                from.push_back(b.integer(0));
                span.push_back(b.integer(0));
                continue;
            }
            ValueId l = b.op(Op::FloorInt, {b.op(Op::Extract, {lo}, a)});
            ValueId h = b.op(Op::FloorInt, {b.op(Op::Extract, {hi}, a)});
            from.push_back(l);
            span.push_back(b.op(Op::Sub, {h, l}));
        }
        // One loop per axis of more than one cell, layers (z), rows (y), cells (x) from the outside in: no integer
        // division (scalarised on SIMD CPUs). An axis of one cell (a lattice in a plane: 10×10×1) is no loop and no
        // test: its one cell holds the nearest member, whose distance sets the reach, so it is always in reach (a loop
        // of 0 or 1 trips around the others made 100 instances' frame 13% slower; a test of its span, always true
        // as lo and hi are clamped to that cell, cost 100 instances' compile ~1%).
        auto stride = [&](Builder& lb, int a, ValueId k, ValueId first, ValueId step) {
            if (L.stride[size_t(a)] == 0) return k;
            return lb.op(Op::Add, {k, lb.op(Op::Mul, {lb.integer(L.stride[size_t(a)]), lb.op(Op::Add, {first, step})})});
        };
        const std::string name = "iqc_scene." + it.name;
        std::vector<int> axes;  // looped, outer to inner
        ValueId k_fixed = b.integer(L.base);
        for (int a : {2, 1, 0})
            if (L.n[size_t(a)] > 1) axes.push_back(a);
        static const char* kLevel[] = {"cells", "rows", "layers"};
        static const char* kAxis[] = {"x", "y", "z"};
        // vals: p, k so far, the cell's x, y, z (ints: looped axes' are set by their loops), then the first cell
        // and span of each axis still to loop.
        std::function<std::vector<ValueId>(Builder&, size_t, const std::vector<ValueId>&, const std::vector<ValueId>&)> nest =
            [&](Builder& lb, size_t level, const std::vector<ValueId>& s, const std::vector<ValueId>& vals) -> std::vector<ValueId> {
            if (level == axes.size()) {
                ValueId k = vals[1];
                std::vector<ValueId> next;
                if (alike || centred) {
                    const ValueId cell = lb.construct(Type::vector(3), {vals[2], vals[3], vals[4]});
                    next = alike ? member_step(lb, it, vals[0], k, s, true, moved(lb, vals[0], cell), lb.integer(L.base))
                                 : member_step(lb, it, vals[0], k, s, true, to_centre(lb, vals[0], cell), ValueId(-1), it.centred_fn);
                } else {
                    next = member_step(lb, it, vals[0], k, s, true);
                }
                // The nearest cell's member comes round again: evaluated twice, it gives the distance it gave (the
                // minimum and its id stay); a branch to skip it cost more than that on llvmpipe, which runs both
                // arms (100 instances: compile 3%, frame 2%). Only an empty cell (a part-filled last layer) is skipped.
                if (L.back_axis < 0) return next;
                ValueId skip = lb.op(Op::Or, {lb.compare(CompareKind::Lt, k, lb.integer(0)), lb.compare(CompareKind::Ge, k, lb.integer(L.members))});
                const ValueId unchanged = lb.construct(vt, s);
                const ValueId with = lb.construct(vt, next);
                ValueId chosen = lb.if_(skip, unchanged, with);
                std::vector<ValueId> out;
                for (size_t c = 0; c < s.size(); ++c) out.push_back(lb.op(Op::Extract, {chosen}, int(c)));
                return out;
            }
            const int a = axes[level];
            std::vector<std::pair<std::string, ValueId>> captures = {{"p", vals[0]}, {"k" + std::string(kAxis[a]), vals[1]},
                                                                     {"cx", vals[2]}, {"cy", vals[3]}, {"cz", vals[4]}};
            for (size_t j = level; j < axes.size(); ++j) {
                captures.push_back({std::string("first_") + kAxis[axes[j]], vals[5 + 2 * (j - level)]});
                captures.push_back({std::string("span_") + kAxis[axes[j]], vals[6 + 2 * (j - level)]});
            }
            ValueId hi = vals[6];
            std::string source;
            if (level == 0) {
                source = fmt::format("{}: {} instances on a {}×{}×{} lattice: the cells within reach (each member within {} of its centre{})",
                                     it.name, it.members.size(), L.n[0], L.n[1], L.n[2], glsl::float_literal(bound_of(it.members[0])),
                                     it.derived_bound ? ", derived from the shape" : "");
            }
            return counted_loop(lb, name + "." + kLevel[a], hi, s, captures, source,
                                [&](Builder& ib, ValueId q, const std::vector<ValueId>& s2, const std::vector<ValueId>& cap) {
                                    std::vector<ValueId> inner = {cap[0], stride(ib, a, cap[1], cap[5], q), cap[2], cap[3], cap[4]};
                                    inner[size_t(2 + a)] = ib.op(Op::Add, {cap[5], q});
                                    for (size_t j = 7; j < cap.size(); ++j) inner.push_back(cap[j]);
                                    return nest(ib, level + 1, s2, inner);
                                });
        };
        std::vector<ValueId> vals = {p, k_fixed, from[0], from[1], from[2]};
        for (int a : axes) {
            vals.push_back(from[size_t(a)]);
            vals.push_back(span[size_t(a)]);
        }
        std::vector<ValueId> near = nest(b, 0, st1, vals);
        const ValueId looked_up = b.construct(vt, near);
        // The stand-in serves only points beyond far_from of the lattice's box. Where every call of iqc_scene
        // lies in the scene's box (marches are clipped to it; soft shadows and ambient occlusion, which read the
        // scene anywhere, are off) and that box lies within far_from of the lattice's on every axis, it would
        // never serve, and its test is left out (100 instances: 3% of llvmpipe's driver compile). The lookup
        // is exact anywhere; a point a little outside (a relaxed step's overshoot) only visits more cells.
        bool stand_in_serves = o_.unbounded_scene || !out_.box;
        for (size_t a = 0; a < 3 && !stand_in_serves; ++a)
            stand_in_serves = out_.box->first[a] < centre[a] - half[a] - far_from || out_.box->second[a] > centre[a] + half[a] + far_from;
        ValueId chosen = looked_up;
        if (stand_in_serves) chosen = b.if_(b.compare(CompareKind::Gt, box, b.scalar(far_from)), far, looked_up);
        std::vector<ValueId> out;
        for (size_t c = 0; c < st.size(); ++c) out.push_back(b.op(Op::Extract, {chosen}, int(c)));
        return out;
    }

    // Level l of a group's bounding-volume hierarchy: its nodes [base, base + hi] (base -1: the top level, from 0); a
    // node whose box is no nearer than the nearest distance so far is skipped with everything below it.
    std::vector<ValueId> tree_loop(Builder& outer, const Item& it, size_t l, ValueId p, ValueId base, ValueId hi,
                                   const std::vector<ValueId>& states, bool bounded) {
        std::vector<std::pair<std::string, ValueId>> captures = {{"p", p}};
        if (base != ValueId(-1)) captures.push_back({"first", base});
        std::string name = fmt::format("{}{}.level{}", bounded ? "iqc_scene." : "iqc_scene_unbounded.", it.name, l + 1);
        std::string source = l == 0 ? fmt::format("{}: {} instances, a bounding-box hierarchy of {} level{}", it.name, it.members.size(),
                                                   it.tree.levels.size(), it.tree.levels.size() == 1 ? "" : "s")
                                     : "";
        return counted_loop(outer, name, hi, states, captures, source, [&](Builder& b, ValueId k, const std::vector<ValueId>& st,
                                                                            const std::vector<ValueId>& cap) {
            const Item::TreeLevel& g = it.tree_globals[l];
            ValueId node = cap.size() > 1 ? b.op(Op::Add, {cap[1], k}) : k;
            // The distance to the node's box (0 inside): ‖max(|p - c| - h, 0)‖.
            ValueId outside = b.op(Op::Sub, {b.builtin("abs", {b.op(Op::Sub, {cap[0], read(b, g.center, node)})}), read(b, g.half, node)});
            ValueId ds = b.builtin("length", {b.builtin("max", {outside, b.constant(Type::vector(3), {0, 0, 0})})});
            ds = b.named(ds, "node", "distance to the node's bounding box");
            ValueId enter = b.compare(CompareKind::Lt, ds, st[0]);
            // (spheres over the members' hull: every node entered while some member's values are outside it)
            ValueId valid = it.hull_valid >= 0 ? b.compare(CompareKind::Gt, b.global(it.hull_valid), b.scalar(0.5)) : ValueId(-1);
            if (valid != ValueId(-1)) enter = b.op(Op::Or, {enter, b.compare(CompareKind::Le, b.global(it.hull_valid), b.scalar(0.5))});
            ValueId first = read(b, g.first, node);
            ValueId last = b.op(Op::Sub, {read(b, g.count, node), b.integer(1)});
            std::vector<ValueId> inner = l + 1 < it.tree.levels.size() ? tree_loop(b, it, l + 1, cap[0], first, last, st, bounded)
                                                                      : member_loop(b, it, cap[0], first, last, st, bounded, "");
            Type vt = Type::vector(int(st.size()));
            ValueId below = b.construct(vt, inner);
            if (bounded) {
                // Farther from the node's box than the bound margin and than the box's own half-diagonal, the
                // box's distance stands for everything below it, as `bound` does for one member: a lower bound
                // of the members' distances (at least a third of the nearest one's), which no hit test accepts.
                // Its id is -1, no instance: at the step cap a ray whose last sample is a stand-in is no hit.
                ValueId reach = b.builtin("max", {b.builtin("length", {read(b, g.half, node)}), b.scalar(o_.bound_margin)});
                ValueId far = b.compare(CompareKind::Gt, ds, reach);
                if (valid != ValueId(-1)) far = b.op(Op::And, {far, valid});
                std::vector<ValueId> stand_in = {ds, b.scalar(-1)};
                if (st.size() > 2) stand_in.push_back(st[2]);
                below = b.if_(far, b.construct(vt, stand_in), below);
            }
            ValueId chosen = b.if_(enter, below, b.construct(vt, st));
            std::vector<ValueId> next;
            for (size_t c = 0; c < st.size(); ++c) next.push_back(b.op(Op::Extract, {chosen}, int(c)));
            return next;
        });
    }

    // A group in iqc_scene: the nearest member kept, over its bounding-volume hierarchy when it has one (in
    // iqc_scene_unbounded only for exact shapes, whose distances are at least their sphere's), else
    // k = 0..N-1 over its per-instance data.
    ValueId group_loop(Builder& outer, const Item& it, ValueId p, ValueId res, bool bounded) {
        const bool counted = o_.instrument && bounded;
        const int width = counted ? 3 : 2;
        std::vector<ValueId> states;
        for (int c = 0; c < width; ++c) states.push_back(outer.op(Op::Extract, {res}, c));
        std::vector<ValueId> out;
        if (bounded && it.lattice.found())
            out = lattice_lookup(outer, it, p, states);
        else if (!it.tree.levels.empty() && (bounded || it.exact))
            out = tree_loop(outer, it, 0, p, ValueId(-1), outer.integer(int(it.tree.levels[0].nodes.size()) - 1), states, bounded);
        else
            out = member_loop(outer, it, p, ValueId(-1), outer.integer(int(it.members.size()) - 1), states, bounded,
                              fmt::format("{}: {} instances", it.name, it.members.size()));
        return outer.named(outer.construct(Type::vector(width), out), "res");
    }

    // Member k's lattice cell (ℝ³, whole numbers) from k (ℤ, the member's index in its group), by integer
    // division by the lattice's strides, largest first: k = base + cell·stride (InstanceLattice). -1 where `it`
    // is no lattice group with centred members (Item::centred_fn), or where that division does not give every
    // member's cell back (checked here for every k: a stride that is not a mixed radix, or negative).
    ValueId lattice_cell_of(Builder& b, const Item& it, ValueId k) {
        const InstanceLattice& L = it.lattice;
        if (!it.group || !L.found() || it.centred_fn < 0) return ValueId(-1);
        std::vector<size_t> axes;
        for (size_t a = 0; a < 3; ++a)
            if (L.n[a] > 1) axes.push_back(a);
        std::sort(axes.begin(), axes.end(), [&](size_t x, size_t y) { return L.stride[x] > L.stride[y]; });
        for (size_t a : axes)
            if (L.stride[a] <= 0) return ValueId(-1);
        for (long long m = 0; m < (long long)it.members.size(); ++m) {
            long long r = m - L.base, back = L.base;
            if (r < 0) return ValueId(-1);
            for (size_t a : axes) {
                long long c = r / L.stride[a];
                if (c >= L.n[a]) return ValueId(-1);
                back += c * L.stride[a];
                r -= c * L.stride[a];
            }
            if (r != 0 || back != m) return ValueId(-1);
        }
        std::vector<ValueId> c(3, ValueId(-1));
        // r ∈ [0, members - base): k is a member's index (the callers' ids are in range).
        ValueId r = b.op(Op::Sub, {k, b.integer(L.base)});
        long long n = (long long)it.members.size() - L.base;
        for (size_t i = 0; i < axes.size(); ++i) {
            const long long s = L.stride[axes[i]];
            c[axes[i]] = b.div_by_constant(r, s, n);
            if (i + 1 < axes.size()) r = b.mod_by_constant(r, s, n), n = std::min(n, s);
        }
        for (auto& x : c)
            if (x == ValueId(-1)) x = b.scalar(0);
        return b.construct(Type::vector(3), c);
    }

    // iqc_distance_of(p, id): the instance's own distance (what the analytic normal differentiates, and what
    // finite-difference normals take their taps of), and, for analytic normals, the placeholder iqc_gradient
    // that the gradient pass replaces.
    void gradient_functions() {
        ir::Function f;
        f.name = ir::names::kDistanceOf;
        f.glsl_name = f.name;
        Builder b(m_, f);
        ValueId p = b.param("p", Type::vector(3));
        ValueId id = b.param("id", Type::integer());
        std::vector<std::tuple<long long, long long, ValueId>> cases;
        for (const Item& it : items_) {
            std::vector<ValueId> args = {p};
            if (it.group) args.push_back(b.op(Op::Sub, {id, b.integer(it.id)}));
            bool blend_first = it.blend >= 0 && &items_[blend_items_[size_t(it.blend)][0]] == &it;
            // With glows, the distance without the bound sphere (equal to it near the surface, where normals tap).
            int fn = o_.distance_of && it.unbounded_fn >= 0 ? it.unbounded_fn : it.distance_fn;
            // A lattice's member whose own turn makes its offset no arithmetic on the index (the tables pass makes
            // the offsets of members alike but for their place arithmetic) is evaluated as iqc_scene evaluates it,
            // at p minus its cell's centre (the cell computed from the id): no table of per-member offsets (100
            // instances: a vec3[100] that only this function read, 3-4% of llvmpipe's driver compile).
            ValueId cell = !blend_first && fn == it.distance_fn ? lattice_cell_of(b, it, args.back()) : ValueId(-1);
            ValueId d;
            if (blend_first) {
                d = blend_distance(b, it.blend, p, true, o_.instrument, nullptr);
            } else if (cell != ValueId(-1)) {  // member k at p moved to its cell's centre (lattice_cell_of: centred)
                d = b.call(it.centred_fn, {to_cell_centre(b, it.lattice, p, cell), args.back()});
            } else {
                d = b.call(fn, args);
            }
            // Instrumented, the bounded distance (and a blend) also returns the shapes it evaluated; the distance
            // without its bound sphere (glows) does not.
            if (o_.instrument && (blend_first || fn == it.distance_fn)) d = b.op(Op::Extract, {d}, 0);
            cases.push_back({it.id, it.id + (long long)it.members.size(), d});
        }
        f.result = b.switch_(id, b.scalar(2 * o_.max_dist), std::move(cases));
        f.entry = !o_.analytic_normals || o_.distance_of;  // finite-difference normals and glows call it; the gradient pass reads it
        m_.functions.push_back(std::move(f));
        if (o_.segment) {
            // Placeholders the segment pass fills; where it derives nothing they stay: a gain of 1 (a
            // sphere-tracing step) and -1e30 (no segment is known clear).
            auto placeholder = [&](const char* name, std::vector<const char*> params, double value) {
                ir::Function s;
                s.name = name;
                s.glsl_name = s.name;
                s.entry = true;
                Builder sb(m_, s);
                for (const char* p : params) sb.param(p, Type::vector(3));
                s.result = sb.scalar(value);
                m_.functions.push_back(std::move(s));
            };
            placeholder(ir::names::kSegmentGain, {"lo", "hi", "rd"}, 1);
            placeholder(ir::names::kSegmentClear, {"lo", "hi"}, -1e30);
        }
        if (!o_.analytic_normals) return;
        ir::Function g;
        g.name = ir::names::kGradient;
        g.glsl_name = g.name;
        g.entry = true;
        Builder gb(m_, g);
        gb.param("p", Type::vector(3));
        gb.param("id", Type::integer());
        g.result = gb.constant(Type::vector(3), {0, 0, 0});
        m_.functions.push_back(std::move(g));
    }

    // ---- materials ----

    // The cases of a dispatch on the instance id: per item, the value `of` gives (or none). A blend is one
    // case, at its first member's id: with the point `p`, its members' values weighted as blend_distance
    // weights them (a member without a value counts as `fallback`); without p, its first member's value.
    template <class F>
    std::vector<std::tuple<long long, long long, ValueId>> cases(Builder& b, ValueId id, F of, ValueId p = ValueId(-1),
                                                                 ValueId fallback = ValueId(-1)) {
        std::vector<std::tuple<long long, long long, ValueId>> out;
        for (const Item& it : items_) {
            ValueId k = it.group ? b.op(Op::Sub, {id, b.integer(it.id)}) : ValueId(-1);
            ValueId v = ValueId(-1);
            if (it.blend >= 0 && p != ValueId(-1)) {
                const auto& members = blend_items_[size_t(it.blend)];
                if (&items_[members[0]] != &it) continue;
                // One material with the same values throughout: the weights sum to 1, the first member's value is it.
                bool alike = true;
                for (size_t m : members) {
                    const InstancePlan& a = plan(items_[m].members[0]);
                    const InstancePlan& z = plan(it.members[0]);
                    alike &= a.material == z.material && a.material_values == z.material_values;
                }
                if (alike) {
                    v = of(it, k);
                    if (v != ValueId(-1)) out.push_back({it.id, it.id + 1, v});
                    continue;
                }
                std::vector<ValueId> vs;
                bool any = false;
                for (size_t m : members) {
                    vs.push_back(of(items_[m], ValueId(-1)));
                    any |= vs.back() != ValueId(-1);
                }
                if (!any) continue;
                std::vector<ValueId> w;
                blend_distance(b, it.blend, p, true, o_.instrument, &w);
                for (size_t m = 0; m < vs.size(); ++m) {
                    ValueId term = b.op(Op::Mul, {w[m], vs[m] == ValueId(-1) ? fallback : vs[m]});
                    v = m == 0 ? term : b.op(Op::Add, {v, term});
                }
                v = b.named(v, "blended");
            } else {
                if (it.blend >= 0 && &items_[blend_items_[size_t(it.blend)][0]] != &it) continue;
                v = of(it, k);
            }
            if (v != ValueId(-1)) out.push_back({it.id, it.id + (long long)it.members.size(), v});
        }
        return out;
    }

    void shade_functions() {
        // iqc_shade(id, p, N, eye[, w_P]): each material's light-independent part (ambient, emission, the indirect
        // light C_A): the whole colour of a material no light binds; of one lit once per light, the terms of its
        // colour's sum that read neither P_L nor C_L (material_part). Ambient occlusion darkens this part
        // only, a shadow only its light's part. The default material shows the normal. The pixel's footprint
        // w_P is a parameter only when some material reads it.
        for (const Item& it : items_) out_.binds_footprint |= plan(it.members[0]).binds_footprint();
        {
            ir::Function f;
            f.name = ir::names::kShade;
            f.glsl_name = f.name;
            f.entry = true;
            Builder b(m_, f);
            ValueId id = b.param("id", Type::integer());
            ValueId p = b.param("p", Type::vector(3)), N = b.param("N", Type::vector(3)), eye = b.param("eye", Type::vector(3));
            ValueId W = out_.binds_footprint ? b.param(kFootprint, Type::vector(3)) : ValueId(-1);
            ValueId zero = b.constant(Type::vector(3), {0, 0, 0});
            ValueId normal_colour = b.op(Op::Add, {b.constant(Type::vector(3), {0.5, 0.5, 0.5}), b.op(Op::Mul, {b.scalar(0.5), N})});
            ValueId CA = ValueId(-1);
            for (const Item& it : items_) out_.binds_ambient |= binds_ambient(plan(it.members[0]));
            auto ambient = [&]() {
                if (CA == ValueId(-1) && ambient_lights_) CA = b.call(ambient_function(), {N});
                return CA;
            };
            auto cs = cases(b, id, [&](const Item& it, ValueId k) -> ValueId {
                const InstancePlan& first = plan(it.members[0]);
                if (!first.material) return ValueId(-1);
                bool lit = first.per_light(bind_lights_);
                int fn = lit ? material_part(*first.material, false) : -1;
                if (lit && fn < 0) return zero;  // every term reads the light: iqc_shade_light
                return material_call(b, it, k, p, N, eye, lit ? zero : ValueId(-1), lit ? zero : ValueId(-1), fn,
                                     binds_ambient(first) ? ambient() : ValueId(-1), W);
            }, p, normal_colour);
            f.result = b.named(b.switch_(id, normal_colour, std::move(cs)), "c");
            m_.functions.push_back(std::move(f));
        }
        bool any = false;
        for (const Item& it : items_) any |= plan(it.members[0]).per_light(bind_lights_);
        if (!any || !lights_) return;  // no point light or sun: a lit material shows its light-independent part only
        out_.has_shade_light = true;
        {
            ir::Function f;
            f.name = ir::names::kShadeLight;
            f.glsl_name = f.name;
            f.entry = true;
            Builder b(m_, f);
            ValueId id = b.param("id", Type::integer());
            ValueId p = b.param("p", Type::vector(3)), N = b.param("N", Type::vector(3)), eye = b.param("eye", Type::vector(3));
            ValueId W = out_.binds_footprint ? b.param(kFootprint, Type::vector(3)) : ValueId(-1);
            ValueId PL = b.param("P_L", Type::vector(3)), CL = b.param("C_L", Type::vector(3));
            ValueId CA = ValueId(-1);
            auto cs = cases(b, id, [&](const Item& it, ValueId k) -> ValueId {
                const InstancePlan& first = plan(it.members[0]);
                if (!first.per_light(bind_lights_)) return ValueId(-1);
                int fn = material_part(*first.material, true);
                if (fn < 0) return ValueId(-1);  // no term reads the light
                if (binds_ambient(first) && CA == ValueId(-1)) CA = b.call(ambient_function(), {N});
                return material_call(b, it, k, p, N, eye, PL, CL, fn, binds_ambient(first) ? CA : ValueId(-1), W);
            }, p, b.constant(Type::vector(3), {0, 0, 0}));
            f.result = b.named(b.switch_(id, b.constant(Type::vector(3), {0, 0, 0}), std::move(cs)), "c");
            m_.functions.push_back(std::move(f));
        }
        for (int which = 0; which < 2; ++which) {
            ir::Function f;
            f.name = which == 0 ? ir::names::kLightPosition : ir::names::kLightColor;
            f.glsl_name = f.name;
            f.entry = true;
            Builder b(m_, f);
            ValueId l = b.param("l", Type::integer());
            std::vector<std::tuple<long long, long long, ValueId>> cs;
            const auto& gl = which == 0 ? light_pos_ : light_col_;
            for (size_t i = 0; i < gl.size(); ++i) cs.push_back({(long long)i, (long long)i + 1, b.global(gl[i])});
            f.result = b.named(b.switch_(l, b.constant(Type::vector(3), {0, 0, 0}), std::move(cs)), which == 0 ? "position" : "colour");
            m_.functions.push_back(std::move(f));
        }
    }

    bool binds_ambient(const InstancePlan& first) const {
        return first.material && first.lit_by(first.material->find_param(kAmbientColor), bind_lights_, ambient_lights_);
    }

    // A call of the item's material (or of one part of it, `fn`) with the renderer's bindings: the roles, the
    // light (P_L, C_L) where given, the indirect light C_A and the pixel's footprint W where given.
    ValueId material_call(Builder& b, const Item& it, ValueId k, ValueId p, ValueId N, ValueId eye, ValueId PL, ValueId CL,
                          int fn = -1, ValueId CA = ValueId(-1), ValueId W = ValueId(-1)) {
        const InstancePlan& first = plan(it.members[0]);
        const CheckedModule& mat = *first.material;
        std::map<int, ValueId> bound = {{mat.roles[0], p}, {mat.roles[1], N}, {mat.roles[2], eye}};
        if (PL != ValueId(-1)) {
            bound[mat.find_param(kLightPosition)] = PL;
            if (int c = mat.find_param(kLightColor); first.lit_by(c, bind_lights_)) bound[c] = CL;
        }
        if (CA != ValueId(-1)) bound[mat.find_param(kAmbientColor)] = CA;
        if (W != ValueId(-1) && first.binds_footprint()) bound[mat.find_param(kFootprint)] = W;
        return b.call(fn >= 0 ? fn : lower_module_cached(mat, ctx_), module_args(b, mat, it.material_params, bound, k));
    }

    // One part of a lit material's colour C: its additive terms (C's sum, through +, − and copies) that read
    // the light (P_L or C_L: `light`), or those that do not (the ambient part). Exact for every material affine
    // in the light (C = A + f(P_L)∘C_L): a shadow scales the light's terms, not the ambient ones. A colour that
    // is not a sum is one term. Returns the function computing that part (the material's own when every term
    // is in it), or -1 when no term is.
    int material_part(const CheckedModule& mat, bool light) {
        int fn = lower_module_cached(mat, ctx_);
        auto key = std::make_pair(fn, light);
        if (auto c = parts_.find(key); c != parts_.end()) return c->second;
        ir::Function g = m_.functions[size_t(fn)];
        std::vector<char> reads(g.body.size(), 0);
        int pl = mat.find_param(kLightPosition), cl = mat.find_param(kLightColor);
        for (size_t i = 0; i < g.body.size(); ++i) {
            const ir::Instr& in = g.body[i];
            if (in.op == Op::Param) reads[i] = in.aux == pl || in.aux == cl;
            for (ValueId a : in.args) reads[i] |= reads[a];
        }
        // The terms, distributing products and quotients over sums where that separates light terms from the
        // rest: 0.5(C_L∘x + k_a) → 0.5(C_L∘x) + 0.5k_a, (C_L∘x + k_a)∘(C_A + k_d) → four products. New products
        // are appended to the copy g (used only when the part is a new function); at most 64 terms.
        Builder tb(m_, g);
        std::function<std::vector<std::pair<ValueId, bool>>(ValueId, int)> expand = [&](ValueId v, int depth) {
            std::vector<std::pair<ValueId, bool>> one = {{v, false}};
            const ir::Instr in = g.body[v];  // a copy: g.body grows below
            if (depth > 16) return one;
            auto same = [&](ValueId a) { return g.body[a].type == in.type; };
            if ((in.op == Op::Add || in.op == Op::Sub) && same(in.args[0]) && same(in.args[1])) {
                auto a = expand(in.args[0], depth + 1), b = expand(in.args[1], depth + 1);
                for (auto& t : b) a.push_back({t.first, in.op == Op::Sub ? !t.second : t.second});
                return a.size() > 64 ? one : a;
            }
            if ((in.op == Op::Neg || in.op == Op::Copy) && same(in.args[0])) {
                auto a = expand(in.args[0], depth + 1);
                if (in.op == Op::Neg)
                    for (auto& t : a) t.second = !t.second;
                return a;
            }
            if (!reads[v] || !(in.op == Op::Mul || in.op == Op::Hadamard || in.op == Op::Div)) return one;
            auto a = expand(in.args[0], depth + 1);
            auto b = in.op == Op::Div ? one : expand(in.args[1], depth + 1);
            if (in.op == Op::Div) b = {{in.args[1], false}};
            if (a.size() * b.size() > 64 || a.size() * b.size() == 1) return one;
            bool separates = false;
            for (auto& x : a)
                for (auto& y : b) separates |= !reads[x.first] && !reads[y.first];
            if (!separates) return one;
            std::vector<std::pair<ValueId, bool>> out;
            for (auto& x : a)
                for (auto& y : b) {
                    ValueId prod = tb.op(in.op, {x.first, y.first});
                    reads.resize(g.body.size(), 0);
                    reads[prod] = reads[x.first] || reads[y.first];
                    out.push_back({prod, x.second != y.second});
                }
            return out;
        };
        std::vector<std::pair<ValueId, bool>> terms = expand(g.result, 0);
        reads.resize(g.body.size(), 0);
        std::vector<std::pair<ValueId, bool>> chosen;
        for (const auto& t : terms)
            if (bool(reads[t.first]) == light) chosen.push_back(t);
        int out = -1;
        if (chosen.size() == terms.size()) {
            out = fn;
        } else if (!chosen.empty()) {
            reads.resize(g.body.size(), 0);
            g.name += light ? ".light" : ".ambient";
            g.glsl_name += light ? "_light" : "_ambient";
            g.entry = false;
            Builder b(m_, g);
            ValueId sum = ValueId(-1);
            for (auto [v, neg] : chosen) {
                if (sum == ValueId(-1)) sum = neg ? b.op(Op::Neg, {v}) : v;
                else sum = b.op(neg ? Op::Sub : Op::Add, {sum, v});
            }
            g.result = sum;
            m_.functions.push_back(std::move(g));
            out = int(m_.functions.size() - 1);
        }
        parts_[key] = out;
        return out;
    }

    // iqc_reflectivity(id) -> k_r as ℝ³, or iqc_transmission(id) -> (k_t, η); false when no material has it.
    bool material_property(const char* name) {
        bool reflect = std::string(name) == ir::names::kReflectivity;
        ir::Function f;
        f.name = name;
        f.glsl_name = name;
        f.entry = true;
        Builder b(m_, f);
        ValueId id = b.param("id", Type::integer());
        auto as_vec3 = [&](const Item& it, ValueId k, int param) -> ValueId {
            const CheckedModule& mat = *plan(it.members[0]).material;
            const Type& t = mat.params[size_t(param)].type;
            if (t != Type::vector(3) && !t.is_scalar()) return ValueId(-1);
            ValueId v = read(b, it.material_params[size_t(param)], k);
            return t.is_scalar() ? b.construct(Type::vector(3), {v, v, v}) : v;
        };
        auto cs = cases(b, id, [&](const Item& it, ValueId k) -> ValueId {
            const CheckedModule* mat = plan(it.members[0]).material;
            if (!mat) return ValueId(-1);
            int param = mat->find_param(reflect ? kReflectivity : kTransmission);
            if (param < 0 || it.material_params[size_t(param)].global < 0) return ValueId(-1);
            ValueId v = as_vec3(it, k, param);
            if (v == ValueId(-1) || reflect) return v;
            int eta = mat->find_param(kRefractiveIndex);
            if (eta < 0) eta = mat->find_param(kRefractiveIndexAscii);
            ValueId e = eta >= 0 && mat->params[size_t(eta)].type.is_scalar() ? read(b, it.material_params[size_t(eta)], k)
                                                                               : b.scalar(1.5);
            return b.construct(Type::vector(4), {v, e});
        });
        if (cs.empty()) return false;
        f.result = b.switch_(id, reflect ? b.constant(Type::vector(3), {0, 0, 0}) : b.constant(Type::vector(4), {0, 0, 0, 1}),
                             std::move(cs));
        m_.functions.push_back(std::move(f));
        return true;
    }

    // ---- per pixel ----

    // iqc_max_singular(L) -> the largest singular value of L, in closed form (the largest eigenvalue of the
    // symmetric LᵀL by the trigonometric method): dividing a distance by it keeps it conservative under any
    // linear map.
    int max_singular_function() {
        if (int f = m_.find("iqc_max_singular"); f >= 0) return f;
        ir::Function f;
        f.name = "iqc_max_singular";
        f.glsl_name = "max_singular";
        Builder b(m_, f);
        ValueId L = b.param("L", Type::matrix(3, 3));
        ValueId A = b.named(b.op(Op::Mul, {b.op(Op::Transpose, {L}), L}), "A", "A = LᵀL");
        auto a = [&](int r, int c) { return b.op(Op::Extract, {A}, r * 3 + c); };
        auto sq = [&](ValueId x) { return b.op(Op::Mul, {x, x}); };
        ValueId p1 = b.named(b.op(Op::Add, {b.op(Op::Add, {sq(a(0, 1)), sq(a(0, 2))}), sq(a(1, 2))}), "off", "off-diagonal squares");
        ValueId q = b.named(b.op(Op::Div, {b.op(Op::Add, {b.op(Op::Add, {a(0, 0), a(1, 1)}), a(2, 2)}), b.scalar(3)}), "q", "q = tr(A)/3");
        ValueId d0 = b.op(Op::Sub, {a(0, 0), q}), d1 = b.op(Op::Sub, {a(1, 1), q}), d2 = b.op(Op::Sub, {a(2, 2), q});
        ValueId p2 = b.op(Op::Add, {b.op(Op::Add, {b.op(Op::Add, {sq(d0), sq(d1)}), sq(d2)}), b.op(Op::Mul, {b.scalar(2), p1})});
        ValueId p = b.named(b.builtin("sqrt", {b.builtin("max", {b.op(Op::Div, {p2, b.scalar(6)}), b.scalar(0)})}), "p", "p = ‖A - qI‖_F/√6");
        ValueId I = b.constant(Type::matrix(3, 3), {1, 0, 0, 0, 1, 0, 0, 0, 1});
        ValueId B = b.op(Op::Div, {b.op(Op::Sub, {A, b.op(Op::Mul, {q, I})}), b.builtin("max", {p, b.scalar(1e-30)})});
        ValueId r = b.builtin("clamp", {b.op(Op::Div, {b.op(Op::Det, {B}), b.scalar(2)}), b.scalar(-1), b.scalar(1)});
        ValueId phi = b.named(b.op(Op::Div, {b.builtin("acos", {r}), b.scalar(3)}), "phi", "φ = acos(det((A - qI)/p)/2)/3");
        ValueId top = b.op(Op::Add, {q, b.op(Op::Mul, {b.op(Op::Mul, {b.scalar(2), p}), b.builtin("cos", {phi})})});
        ValueId general = b.builtin("sqrt", {b.builtin("max", {top, b.scalar(0)})});
        ValueId round = b.builtin("sqrt", {b.builtin("max", {q, b.scalar(0)})});  // LᵀL = qI: every direction alike
        f.result = b.op(Op::Select, {b.compare(CompareKind::Lt, p, b.scalar(1e-12)), round, general});
        m_.functions.push_back(std::move(f));
        return int(m_.functions.size() - 1);
    }

    // A slider global's values tested against intervals: its members (one for an instance; a group's per-member table,
    // each element) and, per component, the interval its values must lie in.
    struct WithinTest {
        int global;
        size_t members;
        std::vector<std::pair<size_t, ir::Interval>> where;
    };

    // An interval's ends in float rounded inward: a value a test with them lets through lies in the interval.
    static std::pair<double, double> inward(const ir::Interval& near) {
        float lo = float(near.lo), hi = float(near.hi);
        if (double(lo) < near.lo) lo = std::nextafter(lo, INFINITY);
        if (double(hi) > near.hi) hi = std::nextafter(hi, -INFINITY);
        return {double(lo), double(hi)};
    }

    // One value's test, member `member` (ℤ; -1 for a global that is no table) and component c within `near`.
    ValueId within_test(Builder& b, const WithinTest& test, ValueId member, size_t c, const ir::Interval& near) {
        const Type& type = m_.globals[size_t(test.global)].type;
        ValueId u = b.global(test.global);
        if (type.is_array()) u = b.op(Op::Index, {u, member});
        ValueId x = (type.is_array() ? type.element() : type).is_scalar() ? u : b.op(Op::Extract, {u}, int(c));
        const auto [lo, hi] = inward(near);
        return b.op(Op::And, {b.compare(ir::CompareKind::Ge, x, b.scalar(lo)), b.compare(ir::CompareKind::Le, x, b.scalar(hi))});
    }

    // Makes iqc_prepare (made where there is none) set the prepared global `out` to 1 where every test holds, else 0:
    // per table length a loop over the members (ir::members_within; its body `iqc_prepare.<what>_<members>`), once
    // per pixel.
    void prepare_within(int out, const std::vector<WithinTest>& tests, const std::string& what) {
        std::map<size_t, std::vector<ir::MemberTest>> by_members;
        for (const WithinTest& test : tests)
            for (const auto& [c, near] : test.where) {
                const auto [lo, hi] = inward(near);
                by_members[test.members].push_back({test.global, int(c), {lo}, {hi}});
            }
        int prep = m_.find(ir::names::kPrepare);
        std::vector<ValueId> states;
        for (const auto& [members, group] : by_members)
            states.push_back(ir::members_within(m_, prep, fmt::format("{}.{}_{}", ir::names::kPrepare, what, members), members, group, {"within"})[0]);
        if (prep < 0) prep = ir::prepare_function(m_);  // (no test: the global is 1)
        out_.has_prepare = true;
        ir::Function& pf = m_.functions[size_t(prep)];
        Builder b(m_, pf);
        ValueId all = states.empty() ? b.scalar(1) : states[0];
        for (size_t j = 1; j < states.size(); ++j) all = b.op(Op::Mul, {all, states[j]});
        pf.outputs.push_back({m_.globals[size_t(out)].name, all});
        pf.result = pf.outputs[0].second;
    }

    // The groups whose bounding spheres hold over the hull of their members' values (Item::hull_valid): its test.
    void hull_functions() {
        for (const Item& it : items_) {
            if (it.hull_valid < 0) continue;
            std::vector<WithinTest> tests;
            const InstancePlan& first = plan(it.members[0]);
            // (every parameter the renderer sets, a slider or not: a sequence without a range is a uniform too)
            for (size_t k = 0; k < it.shape_params.size(); ++k) {
                const Field& f = it.shape_params[k];
                if (f.global < 0 || int(k) == first.query) continue;
                WithinTest t{f.global, f.array ? it.members.size() : 1, {}};
                for (size_t c = 0; c < first.shape_values[k].size(); ++c) t.where.push_back({c, value_hull(it.members, k, c)});
                if (!t.where.empty()) tests.push_back(std::move(t));
            }
            prepare_within(it.hull_valid, tests, it.name + "_within_hull");
        }
    }

    // iqc_box_lo() and iqc_box_hi(): the box at the sliders' defaults (SceneIR::box_at_defaults) while every slider of
    // every shape is within it (within 1/64 of its range of its default; in a group, every member's), else the box over
    // their ranges. A group of more than 16 members is tested by a loop over them in iqc_prepare, once per pixel (its
    // answer a prepared global the two read); of more than kMaxHullMembers, not made (the box is the whole's constant:
    // 48 bumpy balls on WebGL2 marched the box over their sliders' ranges; trial77).
    void box_functions() {
        if (!out_.box_at_defaults || !out_.box) return;
        ir::Function lo_f, hi_f;
        lo_f.name = lo_f.glsl_name = ir::names::kBoxLo;
        hi_f.name = hi_f.glsl_name = ir::names::kBoxHi;
        lo_f.entry = hi_f.entry = true;
        // Per slider global: its members (one for an instance; a group's per-member table: each element, up to 16) and,
        // per component, the window its values must lie in (shape_intervals' near_default over the members' values).
        std::vector<WithinTest> tests;
        for (const Item& it : items_) {
            const InstancePlan& first = plan(it.members[0]);
            const std::vector<ir::ValueBounds> ranges = parameter_bounds(*first.shape);
            for (size_t k = 0; k < it.shape_params.size() && k < ranges.size(); ++k) {
                const Field& f = it.shape_params[k];
                if (f.global < 0 || int(k) == first.query || ranges[k].input) continue;
                if (f.array && it.members.size() > kMaxHullMembers) {
                    out_.box_at_defaults.reset();
                    return;
                }
                WithinTest t{f.global, f.array ? it.members.size() : 1, {}};
                const size_t n = first.shape_values[k].size();
                for (size_t c = 0; c < n && c < ranges[k].lo.size(); ++c)
                    if (auto near = near_default({ranges[k].lo[c], ranges[k].hi[c]}, value_hull(it.members, k, c))) t.where.push_back({c, *near});
                if (!t.where.empty()) tests.push_back(std::move(t));
            }
        }
        if (tests.empty()) {
            out_.box_at_defaults.reset();
            return;
        }
        auto side = [](const std::array<double, 3>& v) {
            std::vector<double> w(v.begin(), v.end());
            for (double& x : w) x = std::isinf(x) ? std::copysign(1e30, x) : x;
            return w;
        };
        // The large groups' tests: a loop over the members in iqc_prepare (its answer the prepared global
        // iqc_box_members_near).
        int near_global = -1;
        {
            std::vector<WithinTest> large;
            for (const WithinTest& test : tests)
                if (test.members > 16) large.push_back(test);
            if (!large.empty()) {
                near_global = add_prepared("iqc_box_members_near", Type::scalar(),
                                           "1 while every member of a large group has its sliders near their defaults (the scene box's test)");
                prepare_within(near_global, large, "box_members_near");
            }
        }
        for (int hi = 0; hi < 2; ++hi) {
            ir::Function& f = hi ? hi_f : lo_f;
            Builder b(m_, f);
            const auto& near = hi ? out_.box_at_defaults->second : out_.box_at_defaults->first;
            const auto& whole = hi ? out_.box->second : out_.box->first;
            if (side(near) == side(whole)) {  // (this corner is the same: no test)
                f.result = b.constant(Type::vector(3), side(whole));
                continue;
            }
            ValueId in = ValueId(-1);
            for (const WithinTest& test : tests)
                for (size_t member = 0; member < test.members && test.members <= 16; ++member)
                    for (const auto& [c, near] : test.where) {
                        const bool array = m_.globals[size_t(test.global)].type.is_array();
                        const ValueId t = within_test(b, test, array ? b.integer((long long)member) : ValueId(-1), c, near);
                        in = in == ValueId(-1) ? t : b.op(Op::And, {in, t});
                    }
            if (near_global >= 0) {
                const ValueId t = b.compare(ir::CompareKind::Gt, b.global(near_global), b.scalar(0.5));
                in = in == ValueId(-1) ? t : b.op(Op::And, {in, t});
            }
            f.result = b.op(Op::Select, {in, b.constant(Type::vector(3), side(near)), b.constant(Type::vector(3), side(whole))});
        }
        m_.functions.push_back(std::move(lo_f));
        m_.functions.push_back(std::move(hi_f));
    }

    void prepare_function() {
        if (!out_.has_prepare) return;
        ir::Function f;
        f.name = ir::names::kPrepare;
        f.glsl_name = f.name;
        Builder b(m_, f);
        int max_singular = -1;  // found or made once (a search of the functions per item was n² in instances)
        for (const Item& it : items_) {
            if (it.transform_fn < 0) continue;
            if (max_singular < 0) max_singular = max_singular_function();
            std::vector<ValueId> args;
            for (const Field& fld : it.transform_params) args.push_back(read(b, fld, ValueId(-1)));
            ValueId M = b.named(b.call(it.transform_fn, std::move(args)), "M", it.name + ": " + plan(it.members[0]).transform_comment);
            ValueId inv = b.named(b.op(Op::Inverse, {M}), "inv");
            std::vector<ValueId> lin, off;
            for (int r = 0; r < 3; ++r) {
                for (int c = 0; c < 3; ++c) lin.push_back(b.op(Op::Extract, {inv}, r * 4 + c));
                off.push_back(b.op(Op::Extract, {inv}, r * 4 + 3));
            }
            ValueId L = b.construct(Type::matrix(3, 3), lin);
            f.outputs.push_back({m_.globals[size_t(it.to_object.global)].name, L});
            f.outputs.push_back({m_.globals[size_t(it.offset.global)].name, b.construct(Type::vector(3), off)});
            ValueId norm = b.call(max_singular, {L});
            f.outputs.push_back({m_.globals[size_t(it.scale.global)].name, b.op(Op::Div, {b.scalar(1), norm})});
        }
        f.result = f.outputs[0].second;
        m_.functions.push_back(std::move(f));
    }

    // I♥IQ's architecture, for `iqc bench`: per instance (in the scene's order), its transform inverted at
    // each pixel, and its own object-space distance.
    void per_instance_functions() {
        for (int which = 0; which < 2; ++which) {
            ir::Function f;
            f.name = which == 0 ? ir::names::kInstanceInverse : ir::names::kInstanceDistance;
            f.glsl_name = f.name;
            f.entry = true;
            Builder b(m_, f);
            ValueId i = b.param("i", Type::integer());
            ValueId q = which == 1 ? b.param("q", Type::vector(3)) : ValueId(-1);
            std::vector<std::tuple<long long, long long, ValueId>> cs;
            for (const Item& it : items_) {
                const InstancePlan& p = plan(it.members[0]);
                ValueId v;
                if (which == 0) {
                    if (!p.has_transform) continue;
                    int tf = it.transform_fn >= 0 ? it.transform_fn : lower_module(*p.transform, p.name + ".transform", p.name + "_transform", ctx_);
                    std::vector<ValueId> args;
                    for (size_t k = 0; k < p.transform->params.size(); ++k)
                        args.push_back(it.transform_fn >= 0 ? read(b, it.transform_params[k], ValueId(-1))
                                                            : b.constant(p.transform->params[k].type, p.transform->params[k].value));
                    v = b.op(Op::Inverse, {b.call(tf, std::move(args))});
                } else {
                    v = b.call(lower_module_cached(*p.shape, ctx_), module_args(b, *p.shape, it.shape_params, {{p.query, q}}, ValueId(-1)));
                    if (p.shape->lipschitz != 1) v = b.op(Op::Div, {v, b.scalar(p.shape->lipschitz)});
                }
                cs.push_back({it.id, it.id + 1, v});
            }
            ValueId fallback = which == 0 ? b.constant(Type::matrix(4, 4), {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1})
                                          : b.scalar(2 * o_.max_dist);
            f.result = b.switch_(i, fallback, std::move(cs));
            m_.functions.push_back(std::move(f));
        }
    }
};

}  // namespace

SceneIR lower_scene(const SceneDesc& scene, const std::vector<InstancePlan>& plans, const SceneLowerOptions& o) {
    SceneLowering l(scene, plans, o);
    return l.run();
}

}  // namespace iqc
