// The scene in double precision: the same IR the shader is generated from, evaluated by the evaluator.
// It is the reference that tests compare rendered depth and normals against (a CPU ray caster), and that
// `iqc bench` measures errors with.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "ir/Eval.h"
#include "scene/Scene.h"

namespace iqc {

struct SceneModel {
    struct Instance {
        int shape_fn = -1;
        int query = 0;                  // which argument is the query point
        std::vector<ir::Value> args;    // shape arguments (the query point's slot is overwritten)
        std::array<double, 9> linear{1, 0, 0, 0, 1, 0, 0, 0, 1};  // world -> object, row-major
        std::array<double, 3> offset{0, 0, 0};
        double scale = 1;               // 1 / Lipschitz factor
        double bound = 0;               // `bound = R`: object-space bounding sphere radius (0: none)
        double bound_margin = 0.1;      // the shader's IQC_BOUND_MARGIN
    };
    ir::Module ir;
    std::vector<Instance> instances;
    CameraDesc camera;
    RenderDesc render;

    // Distance to the scene at p and the nearest instance (-1 for none).
    double distance(const std::array<double, 3>& p, int* id = nullptr) const;
    // The camera ray through the centre of pixel (x, y) of a width×height image (y = 0 is the top row),
    // exactly as the shader builds it.
    void ray(int x, int y, int width, int height, std::array<double, 3>& ro, std::array<double, 3>& rd) const;
    // Sphere tracing in double precision to a tight tolerance; returns t, or -1 for no hit within max_dist.
    double trace(const std::array<double, 3>& ro, const std::array<double, 3>& rd, int* id = nullptr) const;
    // Unit normal by central differences in double precision.
    std::array<double, 3> normal(const std::array<double, 3>& p) const;
};

}  // namespace iqc
