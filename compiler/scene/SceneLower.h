// Scene lowering: the scene itself becomes IR — the functions with fixed names that the runtime template
// calls (ir::names: iqc_scene, iqc_distance_of/iqc_gradient, iqc_shade, iqc_shade_light, iqc_light_*,
// iqc_reflectivity, iqc_transmission, iqc_prepare, and the per-instance baseline's functions), and the
// scene's values as module globals: every instance parameter (a Parameter: the target decides whether it is
// a constant or a uniform), every compile-time fact (a Constant: inverted transforms, Lipschitz scales,
// bounding radii) and every value computed once per pixel (Prepared: a transform that depends on a slider
// or on time).
//
// Instancing: instances of one shape with one material and a transform known at compile time form a group
// (kMinGroup or more): its per-instance data (transforms, parameters, bounds) are arrays indexed by the
// instance's position in the group, the group is one loop in iqc_scene, one case of each dispatch, and a
// parameter whose value every member shares is one value (on targets where parameters are constants).
// Instance ids are numbered so that each group's ids are contiguous. A group of 48 or more members that all
// have `bound` is traversed as a bounding-volume hierarchy of boxes built at compile time (scene/Bvh.h): per
// step, up to 8 box tests per node entered instead of one sphere test per member.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "ir/IR.h"
#include "scene/Plan.h"

namespace iqc {

struct SceneLowerOptions {
    bool params_constant = true;     // parameters are constants (Shadertoy); else uniforms (sliders)
    bool analytic_normals = false;   // iqc_distance_of + a placeholder iqc_gradient (the gradient pass fills it)
    bool instance_normals = false;   // iqc_distance_of for finite-difference normals (taps of the hit instance)
    bool distance_of = false;        // iqc_distance_of for the runtime whatever the normals (glows march it)
    bool segment = false;            // segment tracing: iqc_distance_of + a placeholder iqc_segment_gain (the segment pass fills it)
    bool instrument = false;         // iqc_scene returns a third component: shapes evaluated in this call
    bool per_instance = false;       // I♥IQ's architecture for the benchmark: no groups, per-instance functions
    bool reflections = false;        // the scene reads k_r
    bool refraction = false;         // the scene reads k_t, η
    bool unbounded_scene = false;    // also iqc_scene_unbounded: the scene without `bound` spheres (soft shadows, AO)
    double max_dist = 100;           // the scene distance with nothing in it is twice this
    double bound_margin = 0.1;       // `bound`: the shape is evaluated within this distance of its sphere
    double box_level = 0.1;          // the scene box holds every point whose nearness can be ≤ this (SceneIR::box)
    // Where the camera is known (fixed, or an orbit around a known target), the part of box_level that is the step
    // cap's pixel cone at max_dist need only reach the box's farthest point from the camera: the level is then
    // max(box_level_floor, box_cone · that distance) (at most box_level; Compile.cpp box_level).
    double box_level_floor = 0.1;    // the level without the cone
    double box_cone = 0;             // the cone's radius per unit of distance along a ray (0: box_level as it is)
    std::optional<std::array<double, 3>> box_eye;  // the camera, or an orbit's target
    double box_eye_radius = 0;       // an orbit's radius: the camera anywhere on that sphere around box_eye
    int min_group = 4;               // instances of one kind that become a loop
    // > 0: find the thinnest instance (SceneIR::thinnest), its boxes taken at this level (the hit tolerance): for
    // `fixed` steps' default, which can step over a part thinner than a step (Compile.cpp warns).
    double thickness_level = 0;
    // A hit tolerance relative to the distance along the ray (thickness_level per unit): the camera, from which
    // the band the hit test sees around an instance is the tolerance times its distance.
    std::optional<std::array<double, 3>> thickness_eye;
};

// An instance's thickness as a fixed march's hit test sees it (the hit tolerance's band included): the narrowest
// world width of its shape's box (ir::support_box in object space, at the instances' own parameter values) through
// its transform, or, where the transform keeps shapes and the box is closed, twice the solid's depth
// (ir::deepest_bound: a shell's, a tube's thickness). For a slab, how short a ray's way through it can be.
struct ThinPart {
    double thickness = 0;  // world units
    std::string name;      // the instance, as the user sees it
    Span span;             // its `type`
};

struct SceneIR {
    ir::Module module;
    std::map<std::string, std::string> headers;  // instance -> "torus with phong" (declaration comments)
    int instances = 0;
    int lights = 0;        // point lights and suns (iqc_light_position/colour), point lights first
    int point_lights = 0;  // the first this many are point lights, the rest suns
    bool any_bound = false;
    bool has_prepare = false;
    bool has_shade_light = false;   // some material is evaluated once per light
    bool binds_ambient = false;     // some material reads the sky and bounce lights (C_A)
    bool binds_footprint = false;   // some material reads the pixel's footprint w_P: iqc_shade(_light) take it after eye
    bool has_reflectivity = false;
    bool has_transmission = false;
    // The box every point where an instance's nearness (its world distance before a Lipschitz division) can be
    // within SceneLowerOptions::box_level lies in (lo, hi per axis; ±∞ on an unbounded side): rays are clipped to it.
    // Absent where no side is bounded or the compiler cannot tell (a transform that moves at run time, a blend).
    std::optional<std::pair<std::array<double, 3>, std::array<double, 3>>> box;
    int box_analyses = 0;  // the shapes' boxes analysed for it (ir::support_box calls: a measure of the work)
    // Where sliders are uniforms: the box with every slider of a shape within 1/64 of its range of its default (the
    // picture a page opens with), where narrower than `box`; the IR's entry functions iqc_box_lo/iqc_box_hi pick it
    // while the sliders are there, else `box`.
    std::optional<std::pair<std::array<double, 3>, std::array<double, 3>>> box_at_defaults;
    std::optional<ThinPart> thinnest;      // where SceneLowerOptions::thickness_level asks for it (and one is bounded)
    std::vector<std::string> group_notes;  // "torus with lambert: 1000 instances in one loop"
    std::vector<int> instance_ids;         // per plan: the id iqc_scene returns for it (and iqc_distance_of takes)
    std::vector<std::pair<Span, std::string>> warnings;  // what the lowering chose against the scene's wish, located
    // Per global made for a scene item (index into module.globals): the item's first instance's `type`, where a
    // diagnostic about the global points.
    std::map<int, Span> global_spans;
};

// Lowers the planned instances (plans[i] is scene.instances[i]) with their modules.
SceneIR lower_scene(const SceneDesc& scene, const std::vector<InstancePlan>& plans, const SceneLowerOptions& o);

}  // namespace iqc
