#include "scene/Reference.h"

#include <cmath>

#include "ir/Eval.h"

namespace iqc {

namespace {
using V3 = std::array<double, 3>;
V3 sub(const V3& a, const V3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
V3 cross(const V3& a, const V3& b) { return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]}; }
V3 normalize(const V3& a) {
    double l = std::sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    return {a[0] / l, a[1] / l, a[2] / l};
}
}  // namespace

void SceneModel::init(uint64_t max_steps) {
    scene_fn_ = ir.find(ir::names::kScene);
    ir::EvalInputs inputs;
    inputs.max_steps = max_steps;
    eval_ = std::make_shared<ir::Evaluator>(ir, inputs);
}

double SceneModel::distance(const V3& p, int* id) const {
    double res[3] = {render.max_dist * 2, -1, 0};
    if (scene_fn_ >= 0) {
        const double* args[] = {p.data()};
        eval_->call(scene_fn_, args, res);
    }
    if (id) *id = int(res[1]);
    return res[0];
}

void SceneModel::ray(int x, int y, int width, int height, V3& ro, V3& rd) const {
    double fx = x + 0.5, fy = (height - 1 - y) + 0.5;
    double u = (2 * fx - width) / height, v = (2 * fy - height) / height;
    V3 eye = camera.position;
    V3 forward = normalize(sub(camera.target, eye));
    V3 up = std::fabs(forward[1]) > 0.999 ? V3{0, 0, 1} : V3{0, 1, 0};
    V3 right = normalize(cross(up, forward));
    V3 cam_up = cross(forward, right);
    double focal = 1.0 / std::tan(camera.fov * M_PI / 360.0);
    V3 d = {right[0] * u + cam_up[0] * v + forward[0] * focal, right[1] * u + cam_up[1] * v + forward[1] * focal,
            right[2] * u + cam_up[2] * v + forward[2] * focal};
    ro = eye;
    rd = normalize(d);
}

double SceneModel::trace(const V3& ro, const V3& rd, int* id, double step) const {
    double t = 0, s = 1;
    for (int i = 0; i < 200000; ++i) {
        V3 p = {ro[0] + t * rd[0], ro[1] + t * rd[1], ro[2] + t * rd[2]};
        int hit_id;
        double d = distance(p, &hit_id);
        if (i == 0 && d < 0) s = -1;
        d *= s;
        if (std::fabs(d) < 1e-9 * std::max(1.0, t)) {
            if (id) *id = hit_id;
            return t;
        }
        t += step * d;
        if (t > render.max_dist) break;
    }
    if (id) *id = -1;
    return -1;
}

V3 SceneModel::normal(const V3& p) const {
    double h = 1e-7 * std::max(1.0, std::sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]));
    V3 n;
    for (int k = 0; k < 3; ++k) {
        V3 a = p, b = p;
        a[size_t(k)] += h;
        b[size_t(k)] -= h;
        n[size_t(k)] = distance(a) - distance(b);
    }
    return normalize(n);
}

}  // namespace iqc
