#include "bench/Bench.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <sstream>
#include <map>
#include <set>

#include "glsl/ShadertoyWrapper.h"
#include "render/Render.h"
#include "scene/Compile.h"

namespace iqc::bench {

namespace {

constexpr uint64_t kReferenceEvalSteps = 1'000'000;  // evaluator steps per scene evaluation of the reference
// Evaluator steps the CPU reference may take for the whole image (2–12 s on a 2-core machine of 2026: the
// evaluator ran 0.8–4.7·10⁸ steps a second on the bench scenes), estimated from a sample of pixels. Work, not
// time: a time estimate chose the other reference on a loaded machine, and the report's errors changed with it.
constexpr uint64_t kReferenceWork = 1'000'000'000;

double percentile(std::vector<double> v, double q) {
    if (v.empty()) return 0;
    std::sort(v.begin(), v.end());
    return v[size_t(q * double(v.size() - 1) + 0.5)];
}

std::optional<March> parse_march(const std::string& s) {
    if (s == "fixed") return March::Fixed;
    if (s == "sphere") return March::Sphere;
    if (s == "relaxed") return March::Relaxed;
    if (s == "auto") return March::Auto;
    if (s == "segment") return March::Segment;
    return std::nullopt;
}
std::optional<Normals> parse_normals(const std::string& s) {
    if (s == "central") return Normals::Central;
    if (s == "forward") return Normals::Forward;
    if (s == "tetrahedron") return Normals::Tetrahedron;
    if (s == "analytic") return Normals::Analytic;
    return std::nullopt;
}

struct Setting {
    std::string method;  // a march method, "per_instance" or "oracle"
    double hit;
    int max_steps;
    std::string normals;
};

// A row's frame time as text: "-" where it was not timed (the oracle).
std::string frame_text(const Row& x) { return std::isnan(x.frame_ms) ? "-" : fmt::format("{:.2f}", x.frame_ms); }

struct Geometry {
    std::vector<float> t;      // -1: no hit
    std::vector<float> n;      // 3 per pixel
};

}  // namespace

Report run(const Options& o) {
    Report rep;
    std::string err;
    auto renderer = render::Renderer::create(&err);
    if (!renderer) {
        rep.error = "no headless renderer: " + err;
        return rep;
    }
    rep.renderer = renderer->renderer_name();
    const int W = o.width, H = o.height;
    const size_t N = size_t(W) * size_t(H);

    // A benchmark build (`bench`) takes the hit tolerance, the step cap and the output mode as uniforms.
    auto compile = [&](const Setting& s, bool instrument, bool geometry, bool bench = false) -> CompileResult {
        SourceManager sm;
        Diagnostics d(sm);
        CompileOptions co;
        co.instrument = instrument;
        co.geometry = geometry;
        co.bench = bench;
        co.bench_max_hit = *std::max_element(o.hits.begin(), o.hits.end());
        co.per_instance = s.method == "per_instance";
        co.oracle = s.method == "oracle";
        if (auto m = parse_march(s.method)) co.march = m;
        co.normals = parse_normals(s.normals);
        if (!bench) {
            co.hit = s.hit;
            co.max_steps = s.max_steps;
        }
        CompileResult r = compile_file(o.input, sm, d, co);
        if (r.exit_code != 0) err = d.render() + r.internal;
        return r;
    };
    auto render = [&](const std::string& code, int repeat, render::RenderResult& out) {
        render::RenderOptions ro;
        ro.width = W;
        ro.height = H;
        ro.repeat = repeat;
        out = renderer->render(glsl::wrap_shadertoy(code), ro);
        if (!out.ok) err = out.error;
        return out.ok;
    };

    // The scene's own settings, and the model for the double-precision reference.
    CompileResult base = compile({"sphere", 1e-3, 128, "tetrahedron"}, false, false);
    if (base.exit_code != 0) {
        rep.error = err;
        return rep;
    }
    // The reference's own copy, with a budget per scene evaluation: a scene whose one evaluation takes more
    // than a million evaluator steps (a long recurrence) could not be ray cast on the CPU in any useful time,
    // and the renderer's most accurate setting stands in (below).
    rep.lipschitz = base.lipschitz;
    SceneModel model = *base.model;
    model.init(kReferenceEvalSteps);
    double min_hit = *std::min_element(o.hits.begin(), o.hits.end());
    int max_cap = *std::max_element(o.step_caps.begin(), o.step_caps.end());
    Setting best{"sphere", min_hit, max_cap, "analytic"};

    // Geometry reference: the evaluator when its work fits kReferenceWork (estimated from a sample of 64
    // pixels, or fewer where they already take a sixteenth of it), else the most accurate setting on the
    // renderer.
    Geometry ref;
    ref.t.assign(N, -1);
    ref.n.assign(3 * N, 0);
    {
        int sampled = 0;
        bool over_budget = false;
        try {
            for (int k = 0; k < 64 && model.work() < kReferenceWork / 16; ++k) {
                int x = (k * 37) % W, y = (k * 17) % H;
                std::array<double, 3> ro, rd;
                model.ray(x, y, W, H, ro, rd);
                model.trace(ro, rd);
                ++sampled;
            }
        } catch (const ir::EvalLimit&) {
            over_budget = true;
        }
        double per_pixel = double(model.work()) / std::max(sampled, 1);  // evaluator steps
        bool cpu = !over_budget && per_pixel * double(N) < double(kReferenceWork);
        if (cpu) {
          try {
            for (int y = 0; y < H; ++y) {
                for (int x = 0; x < W; ++x) {
                    std::array<double, 3> ro, rd;
                    model.ray(x, y, W, H, ro, rd);
                    double t = model.trace(ro, rd);
                    size_t i = size_t(y) * size_t(W) + size_t(x);
                    ref.t[i] = float(t);
                    if (t >= 0) {
                        auto n = model.normal({ro[0] + t * rd[0], ro[1] + t * rd[1], ro[2] + t * rd[2]});
                        for (int c = 0; c < 3; ++c) ref.n[3 * i + size_t(c)] = float(n[size_t(c)]);
                    }
                }
                if (o.progress) o.progress(0, 1, fmt::format("reference: row {}/{}", y + 1, H));
            }
            rep.geometry_reference = "the double-precision evaluator (the scene's IR ray cast on the CPU)";
          } catch (const ir::EvalLimit&) {
            over_budget = true;
            cpu = false;
          }
        }
        if (!cpu) {
            CompileResult g = compile(best, false, true);
            render::RenderResult r;
            if (g.exit_code != 0 || !render(g.code, 0, r)) {
                rep.error = err;
                return rep;
            }
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x) {
                    size_t i = size_t(y) * size_t(W) + size_t(x);
                    const float* p = r.image.pixel(x, y);
                    ref.t[i] = p[0];
                    for (int c = 0; c < 3; ++c) ref.n[3 * i + size_t(c)] = p[1 + c];
                }
            rep.geometry_reference =
                over_budget ? fmt::format("the most accurate setting (march {}, hit {}, max_steps {}, normals {}) — one scene "
                                          "evaluation takes more than {} evaluator steps, too many for the CPU",
                                          best.method, best.hit, best.max_steps, best.normals, kReferenceEvalSteps)
                            : fmt::format("the most accurate setting (march {}, hit {}, max_steps {}, normals {}) — the "
                                          "evaluator would take about {:.2g} steps at this size, over its budget of {:.2g}",
                                          best.method, best.hit, best.max_steps, best.normals, per_pixel * double(N),
                                          double(kReferenceWork));
        }
    }
    // Colour reference: the most accurate setting.
    std::vector<float> ref_colour;
    {
        CompileResult c = compile(best, false, false);
        render::RenderResult r;
        if (c.exit_code != 0 || !render(c.code, 0, r)) {
            rep.error = err;
            return rep;
        }
        ref_colour = r.image.rgba;
        rep.colour_reference = fmt::format("march {}, hit {}, max_steps {}, normals {}", best.method, best.hit, best.max_steps,
                                           best.normals);
    }

    std::vector<Setting> settings;
    for (const auto& m : o.marches)
        for (const auto& n : o.normals)
            for (double h : o.hits)
                for (int cap : o.step_caps) settings.push_back({m, h, cap, n});
    // I♥IQ's per-instance march takes each instance alone: it cannot draw a blend.
    if (o.per_instance && !base.blends) settings.push_back({"per_instance", model.render.hit, model.render.max_steps, "tetrahedron"});
    // The floor of the marches certified by overlapping unbounding spheres, with the normals the other
    // methods' table reads and the largest step cap (it has no step cap rules: a ray it takes past the cap is
    // a miss); its frame is a search's, not timed.
    if (o.oracle && !o.step_caps.empty())
        for (double h : o.hits)
            settings.push_back({"oracle", h, *std::max_element(o.step_caps.begin(), o.step_caps.end()), "tetrahedron"});

    // One benchmark build per (method, normals): the hit tolerance, the step cap and the output are uniforms.
    std::string bench_code;
    std::pair<std::string, std::string> built;
    for (size_t si = 0; si < settings.size(); ++si) {
        const Setting& s = settings[si];
        if (o.progress)
            o.progress(int(si), int(settings.size()),
                       fmt::format("{} hit {} max_steps {} normals {}", s.method, s.hit, s.max_steps, s.normals));
        if (built != std::make_pair(s.method, s.normals) || bench_code.empty()) {
            CompileResult r = compile(s, false, false, true);
            if (r.exit_code != 0) {
                rep.error = err;
                return rep;
            }
            bench_code = glsl::wrap_shadertoy(r.code);
            built = {s.method, s.normals};
        }
        auto draw = [&](int mode, int repeat, render::RenderResult& out) {
            render::RenderOptions ro;
            ro.width = W;
            ro.height = H;
            ro.repeat = repeat;
            ro.int_uniforms = {{"iqc_mode", mode}, {"IQC_MAX_STEPS", s.max_steps}};
            ro.uniforms = {{"IQC_HIT", {float(s.hit)}}};
            out = renderer->render(bench_code, ro);
            if (!out.ok) err = out.error;
            return out.ok;
        };
        Row row{s.method, s.hit, s.max_steps, s.normals};
        render::RenderResult rc, ri, rg;
        bool timed = s.method != "oracle";
        if (!draw(0, timed ? o.frames : 0, rc) || !draw(1, 0, ri) || !draw(2, 0, rg)) {
            rep.error = err;
            return rep;
        }
        std::vector<double> times(rc.repeat_ms.begin(), rc.repeat_ms.end());
        row.frame_ms = timed ? percentile(times, 0.5) : std::nan("");
        std::vector<double> evals, depth, angle;
        long mismatch = 0;
        double mse = 0;
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                size_t i = size_t(y) * size_t(W) + size_t(x);
                evals.push_back(ri.image.pixel(x, y)[1]);
                const float* g = rg.image.pixel(x, y);
                bool gh = g[0] >= 0, rh = ref.t[i] >= 0;
                if (gh != rh) ++mismatch;
                if (gh && rh) {
                    depth.push_back(std::fabs(double(g[0]) - ref.t[i]));
                    double gl = std::sqrt(double(g[1]) * g[1] + double(g[2]) * g[2] + double(g[3]) * g[3]);
                    double dotp = gl > 0 ? (g[1] * ref.n[3 * i] + g[2] * ref.n[3 * i + 1] + g[3] * ref.n[3 * i + 2]) / gl : -1;
                    angle.push_back(std::acos(std::clamp(dotp, -1.0, 1.0)) * 180.0 / M_PI);
                }
                const float* c = rc.image.pixel(x, y);
                for (int k = 0; k < 3; ++k) {
                    double a = std::clamp(double(c[k]), 0.0, 1.0), b = std::clamp(double(ref_colour[4 * i + size_t(k)]), 0.0, 1.0);
                    mse += (a - b) * (a - b);
                }
            }
        double sum = 0;
        for (double e : evals) sum += e;
        row.evals_mean = sum / double(evals.size());
        row.evals_p99 = percentile(evals, 0.99);
        row.hit_mismatch_pct = 100.0 * double(mismatch) / double(N);
        row.depth_err_p99 = percentile(depth, 0.99);
        row.normal_err_deg_p99 = percentile(angle, 0.99);
        mse /= double(3 * N);
        row.psnr_db = mse <= 1e-10 ? 100.0 : std::min(100.0, 10.0 * std::log10(1.0 / mse));
        rep.rows.push_back(row);
    }
    if (o.progress) o.progress(int(settings.size()), int(settings.size()), "done");
    return rep;
}

std::string csv(const Report& r) {
    std::string out =
        "method,hit,max_steps,normals,frame_ms,evals_per_pixel_mean,evals_per_pixel_p99,hit_mismatch_pct,depth_err_p99,"
        "normal_err_deg_p99,psnr_db\n";
    for (const auto& x : r.rows)
        out += fmt::format("{},{},{},{},{:.3f},{:.3f},{:.0f},{:.3f},{:.3g},{:.3g},{:.2f}\n", x.method, x.hit, x.max_steps, x.normals,
                           x.frame_ms, x.evals_mean, x.evals_p99, x.hit_mismatch_pct, x.depth_err_p99, x.normal_err_deg_p99,
                           x.psnr_db);
    return out;
}

bool read_csv(const std::string& text, Report& r, std::string* error) {
    std::istringstream in(text);
    std::string line;
    int number = 0;
    r.rows.clear();
    while (std::getline(in, line)) {
        if (++number == 1 || line.empty()) continue;  // the header
        std::vector<std::string> f;
        std::stringstream ls(line);
        for (std::string cell; std::getline(ls, cell, ',');) f.push_back(cell);
        try {
            if (f.size() != 11) throw std::invalid_argument("11 columns");
            Row x;
            x.method = f[0];
            x.hit = std::stod(f[1]);
            x.max_steps = std::stoi(f[2]);
            x.normals = f[3];
            x.frame_ms = std::stod(f[4]);
            x.evals_mean = std::stod(f[5]);
            x.evals_p99 = std::stod(f[6]);
            x.hit_mismatch_pct = std::stod(f[7]);
            x.depth_err_p99 = std::stod(f[8]);
            x.normal_err_deg_p99 = std::stod(f[9]);
            x.psnr_db = std::stod(f[10]);
            r.rows.push_back(x);
        } catch (const std::exception&) {
            if (error) *error = fmt::format("line {}: not a row of iqc bench's CSV (11 columns: {})", number, line.substr(0, 80));
            return false;
        }
    }
    return true;
}

std::string table(const Report& r) {
    std::string out = fmt::format("{:<13} {:>7} {:>6} {:<12} {:>9} {:>10} {:>9} {:>9} {:>10} {:>10} {:>7}\n", "method", "hit",
                                  "steps", "normals", "frame ms", "evals/px", "evals p99", "miss %", "depth p99",
                                  "normal p99", "PSNR");
    for (const auto& x : r.rows)
        out += fmt::format("{:<13} {:>7} {:>6} {:<12} {:>9} {:>10.2f} {:>9.0f} {:>9.3f} {:>10.3g} {:>9.3g}° {:>7.1f}\n", x.method,
                           x.hit, x.max_steps, x.normals, frame_text(x),
                           x.evals_mean, x.evals_p99, x.hit_mismatch_pct, x.depth_err_p99, x.normal_err_deg_p99, x.psnr_db);
    return out;
}

std::string svg(const Report& r, const std::string& title) {
    // Both axes logarithmic: scene evaluations per pixel (exact counts, not a timing) against the 99th
    // percentile depth error. Plain SVG 1.1 (self-closing shapes, attributes only, no CSS; one font family,
    // DejaVu Sans: ImageMagick's renderer takes no list) so ImageMagick and librsvg draw what browsers draw; each point's setting is in a <title>, the Pareto front's also as text.
    const double W = 820, H = 500, L = 80, R = 170, T = 50, B = 60;
    double vmin = 1e300, vmax = 0, emin = 1e300, emax = 0;
    auto err = [](const Row& x) { return std::max(x.depth_err_p99, 1e-7); };
    auto evals = [](const Row& x) { return std::max(x.evals_mean, 1e-3); };
    for (const auto& x : r.rows) {
        vmin = std::min(vmin, evals(x));
        vmax = std::max(vmax, evals(x));
        emin = std::min(emin, err(x));
        emax = std::max(emax, err(x));
    }
    if (r.rows.empty()) return "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"1\" height=\"1\"/>\n";
    double lmin = std::floor(std::log10(emin)), lmax = std::ceil(std::log10(emax));
    if (lmax <= lmin) lmax = lmin + 1;
    double vlo = std::floor(std::log10(vmin)), vhi = std::ceil(std::log10(vmax));
    if (vhi <= vlo) vhi = vlo + 1;
    auto X = [&](double v) { return L + (std::log10(v) - vlo) / (vhi - vlo) * (W - L - R); };
    auto Y = [&](double e) { return T + (lmax - std::log10(e)) / (lmax - lmin) * (H - T - B); };
    std::map<std::string, std::string> colours = {{"fixed", "#7f7f7f"}, {"sphere", "#1f77b4"}, {"relaxed", "#2ca02c"},
                                                  {"auto", "#d62728"}, {"segment", "#ff7f0e"}, {"per_instance", "#9467bd"},
                                                  {"oracle", "#8c564b"}};
    auto setting = [](const Row& x) { return fmt::format("{} hit {:g} steps {} {}", x.method, x.hit, x.max_steps, x.normals); };
    std::string s = fmt::format("<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{}\" height=\"{}\" "
                                "font-family=\"DejaVu Sans\" font-size=\"12\">\n<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"white\"/>\n",
                                W, H, W, H);
    s += fmt::format("<text x=\"{}\" y=\"24\" font-size=\"15\">{}</text>\n", L, title);
    // Axes and grid, a line per decade.
    s += fmt::format("<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>\n", L, H - B, W - R, H - B);
    s += fmt::format("<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>\n", L, T, L, H - B);
    for (double l = vlo; l <= vhi; l += 1) {
        double x = X(std::pow(10, l));
        s += fmt::format("<line x1=\"{:.1f}\" y1=\"{}\" x2=\"{:.1f}\" y2=\"{}\" stroke=\"#dddddd\"/>\n", x, T, x, H - B);
        s += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{:g}</text>\n", x, H - B + 18, std::pow(10, l));
    }
    for (double l = lmin; l <= lmax; l += 1) {
        s += fmt::format("<line x1=\"{}\" y1=\"{:.1f}\" x2=\"{}\" y2=\"{:.1f}\" stroke=\"#dddddd\"/>\n", L, Y(std::pow(10, l)), W - R,
                         Y(std::pow(10, l)));
        s += fmt::format("<text x=\"{}\" y=\"{:.1f}\" text-anchor=\"end\">1e{:.0f}</text>\n", L - 6, Y(std::pow(10, l)) + 4, l);
    }
    s += fmt::format("<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">scene evaluations per pixel (mean, log scale)</text>\n",
                     (L + W - R) / 2, H - 18);
    s += fmt::format("<text x=\"20\" y=\"{}\" text-anchor=\"middle\" transform=\"rotate(-90 20 {})\">depth error, 99th percentile</text>\n",
                     (T + H - B) / 2, (T + H - B) / 2);
    // Pareto front: no other setting needs fewer evaluations and is more accurate (the oracle is a floor, not a
    // setting to draw with).
    std::vector<const Row*> rows;
    for (const auto& x : r.rows)
        if (x.method != "oracle") rows.push_back(&x);
    std::sort(rows.begin(), rows.end(), [&](const Row* a, const Row* b) {
        return evals(*a) != evals(*b) ? evals(*a) < evals(*b) : err(*a) < err(*b);
    });
    std::vector<const Row*> front;
    double best = 1e300;
    for (const Row* x : rows)
        if (err(*x) < best) {
            best = err(*x);
            front.push_back(x);
        }
    std::string points;
    for (const Row* x : front) points += fmt::format("{:.1f},{:.1f} ", X(evals(*x)), Y(err(*x)));
    s += fmt::format("<polyline points=\"{}\" fill=\"none\" stroke=\"black\" stroke-dasharray=\"4,3\"/>\n", points);
    for (const auto& x : r.rows) {
        std::string c = colours.count(x.method) ? colours[x.method] : "black";
        s += fmt::format("<g><title>{}: {} ms, depth p99 {:.3g}, {:.1f} evals/px</title>"
                         "<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3.5\" fill=\"{}\" fill-opacity=\"0.75\"/></g>\n",
                         setting(x), frame_text(x), x.depth_err_p99,
                         x.evals_mean, X(evals(x)), Y(err(x)), c);
    }
    for (size_t k = 0; k < front.size(); ++k)  // the front's settings by name, above and below in turn
        s += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" font-size=\"9\" fill=\"#333333\">{}</text>\n", X(evals(*front[k])) + 6,
                         Y(err(*front[k])) + (k % 2 ? 13 : -5), setting(*front[k]));
    double ly = T + 10;
    for (const auto& entry : colours) {
        const std::string& m = entry.first;  // (clang 14 cannot capture a structured binding in a lambda)
        const std::string& c = entry.second;
        bool present = std::any_of(r.rows.begin(), r.rows.end(), [&](const Row& x) { return x.method == m; });
        if (!present) continue;
        s += fmt::format("<circle cx=\"{}\" cy=\"{}\" r=\"5\" fill=\"{}\"/><text x=\"{}\" y=\"{}\">{}</text>\n", W - R + 20, ly, c,
                         W - R + 32, ly + 4, m);
        ly += 20;
    }
    s += fmt::format("<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\" stroke-dasharray=\"4,3\"/><text x=\"{}\" "
                     "y=\"{}\">Pareto front</text>\n",
                     W - R + 12, ly, W - R + 28, ly, W - R + 32, ly + 4);
    s += "</svg>\n";
    return s;
}

}  // namespace iqc::bench
