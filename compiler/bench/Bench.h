// `iqc bench`: what accuracy costs in time, measured on the user's own scene.
//
// Renders the scene headlessly under a sweep of march methods × hit tolerances × step caps × normal
// methods, plus I♥IQ's architecture (`per_instance`: one march per instance, transforms inverted per
// instance per pixel) and the floor of the marches certified by overlapping unbounding spheres (`oracle`),
// and compares each with a reference: depth and normals from the double-precision evaluator where that is
// feasible at the chosen size (else the most accurate setting on the GPU), colour from the most accurate
// setting. Reports frame time (median of timed frames after a warm-up), distance evaluations per pixel (an
// instrumented build), hit mismatches, depth and normal errors, and PSNR.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace iqc::bench {

struct Options {
    std::string input;
    int width = 160, height = 90;
    int frames = 5;                          // timed frames after one warm-up
    std::vector<std::string> marches = {"fixed", "sphere", "relaxed", "auto", "segment"};
    std::vector<double> hits = {1e-2, 1e-3, 1e-4};
    std::vector<int> step_caps = {64, 256};
    std::vector<std::string> normals = {"central", "forward", "tetrahedron", "analytic"};
    bool per_instance = true;
    // Rows `oracle`: the fewest evaluations any march certified by overlapping unbounding spheres can take
    // (a greedy chain of the farthest samples whose spheres overlap, found by a search it does not count;
    // runtime_templates/scene.glsl MARCH_ORACLE), at every hit tolerance with the largest step cap and
    // tetrahedron normals; frame_ms NaN (not timed).
    bool oracle = true;
    std::function<void(int done, int total, const std::string& what)> progress;
};

struct Row {
    std::string method;
    double hit = 0;
    int max_steps = 0;
    std::string normals;
    double frame_ms = 0;
    double evals_mean = 0, evals_p99 = 0;
    double hit_mismatch_pct = 0;
    double depth_err_p99 = 0;
    double normal_err_deg_p99 = 0;
    double psnr_db = 0;
};

struct Report {
    std::vector<Row> rows;
    std::string renderer;
    std::string geometry_reference;  // "double-precision evaluator" or the setting used
    std::string colour_reference;
    std::vector<std::string> lipschitz;  // the scene's Lipschitz bounds (CompileResult::lipschitz)
    std::string error;               // non-empty: the bench could not run
};

Report run(const Options& o);

std::string csv(const Report& r);
// The rows of a CSV written by csv() (for plotting again without measuring); false with *error (the line)
// on anything else.
bool read_csv(const std::string& text, Report& r, std::string* error);
std::string table(const Report& r);
// An SVG scatter plot of scene evaluations per pixel against depth error (both on log axes), one colour per
// method, the Pareto front drawn and its settings named; plain SVG 1.1 that ImageMagick renders too.
std::string svg(const Report& r, const std::string& title);

}  // namespace iqc::bench
