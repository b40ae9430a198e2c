// The scene in double precision: the same optimized IR the shader is generated from (its iqc_scene
// function, with iqc_prepare's per-pixel values at the parameters' defaults), run by the evaluator. It is
// the reference that tests compare rendered depth and normals against (a CPU ray caster), and that
// `iqc bench` measures errors with.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "ir/Eval.h"
#include "scene/Scene.h"

namespace iqc {

struct SceneModel {
    ir::Module ir;
    CameraDesc camera;
    RenderDesc render;

    // Prepares the evaluator (after `ir` is set; the model must not move afterwards). One scene evaluation
    // may take at most `max_steps` evaluator steps (else ir::EvalLimit is thrown from distance and trace).
    void init(uint64_t max_steps = limits::kMaxEvalSteps);
    // Distance to the scene at p and the nearest instance (-1 for none).
    double distance(const std::array<double, 3>& p, int* id = nullptr) const;
    // The camera ray through the centre of pixel (x, y) of a width×height image (y = 0 is the top row),
    // exactly as the shader builds it.
    void ray(int x, int y, int width, int height, std::array<double, 3>& ro, std::array<double, 3>& rd) const;
    // Sphere tracing in double precision to a tight tolerance; returns t, or -1 for no hit within max_dist.
    // `step` < 1 takes that fraction of each distance: a reference that does not trust the scene's
    // Lipschitz bounds (a field that is steeper than its bound is still found).
    double trace(const std::array<double, 3>& ro, const std::array<double, 3>& rd, int* id = nullptr, double step = 1) const;
    // Unit normal by central differences in double precision.
    std::array<double, 3> normal(const std::array<double, 3>& p) const;
    // Evaluator steps taken so far by every distance, trace and normal (ir::Evaluator::work).
    uint64_t work() const { return eval_ ? eval_->work() : 0; }

private:
    std::shared_ptr<ir::Evaluator> eval_;
    int scene_fn_ = -1;
};

}  // namespace iqc
