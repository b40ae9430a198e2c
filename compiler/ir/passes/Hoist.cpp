#include "ir/passes/Hoist.h"

#include "ir/passes/DCE.h"

#include <algorithm>
#include <fmt/format.h>
#include <functional>
#include <map>
#include <optional>
#include <unordered_map>

namespace iqc::ir {

namespace {

// What every call passes a parameter: a global (not a prepared one) or a constant.
struct Source {
    Op op = Op::Const;
    int aux = 0;  // the global
    Type type;
    std::vector<double> data;  // the constant
    bool operator==(const Source& o) const {
        if (op != o.op || !(type == o.type)) return false;
        if (op == Op::Global) return aux == o.aux;
        if (data.size() != o.data.size()) return false;
        for (size_t k = 0; k < data.size(); ++k)  // by value, NaN equal to NaN
            if (!(data[k] == o.data[k]) && !(data[k] != data[k] && o.data[k] != o.data[k])) return false;
        return true;
    }
};

using Sources = std::vector<std::vector<std::optional<Source>>>;  // per function, per parameter

std::optional<Source> source_of(const Module& m, const Function& f, ValueId v, const std::vector<std::optional<Source>>& own) {
    while (f.body[v].op == Op::Copy) v = f.body[v].args[0];
    const Instr& in = f.body[v];
    if (in.op == Op::Const) return Source{Op::Const, 0, in.type, in.data};
    if (in.op == Op::Global && m.globals[size_t(in.aux)].kind != Global::Kind::Prepared) return Source{Op::Global, in.aux, in.type, {}};
    if (in.op == Op::Param && size_t(in.aux) < own.size()) return own[size_t(in.aux)];
    return std::nullopt;
}

// At most this many float components hoisted in all: each stays live across the whole march, and llvmpipe (AVX2:
// 16 vector registers) compiles a march with more of them live much more slowly. 20 point clouds, each with its own
// hoisted centroid (60 components): first frame at 160x90 33.5 s, 24.7 s with none hoisted, 20.7 s with the first
// five (15 components).
constexpr int kMaxComponents = 16;

bool hoistable_type(const Type& t) {
    return !t.is_array() && (t.is_scalar() || t.is_vector() || t.is_matrix() || t.kind == Type::Integer);
}

}  // namespace

int hoist_pixel_invariants(Module& m) {
    if (m.find(names::kScene) < 0) return 0;
    const size_t nf = m.functions.size();
    // Loop bodies, and what iqc_prepare calls.
    std::vector<char> body(nf, 0), prepares(nf, 0);
    for (const Function& f : m.functions)
        for (const Instr& in : f.body)
            if (in.op == Op::Loop) body[size_t(in.aux)] = 1;
    int prep = m.find(names::kPrepare);
    if (prep >= 0) mark_reachable(m, prep, prepares);
    // The functions the march runs at each step (the scene's distance, an instance's, its gradient, segment
    // tracing's bounds): only there does a value computed per evaluation cost per step. A material runs once per
    // pixel (and light) whatever: hoisting its sums gained nothing and kept their values live across the whole
    // march, and llvmpipe's compile (AVX2: 16 vector registers) fell off a cliff past about 16 such values (a
    // trial's five point clouds, each with a hoisted centroid and a material's hoisted ∑_j v_j: 1.2 s with four,
    // 14 s with five, no first frame in 120 s with six; 0.7 s with the centroids alone).
    std::vector<char> marched(nf, 0);
    for (const char* entry : {names::kScene, names::kSceneUnbounded, names::kDistanceOf, names::kGradient, names::kSegmentGain,
                              names::kSegmentClear, names::kInstanceDistance})
        if (int fn = m.find(entry); fn >= 0) mark_reachable(m, fn, marched);
    // Per function, transitively through its calls and loops: whether it reads a prepared global (per pixel, computed
    // in order by iqc_prepare: a call reading one is left alone) and whether it runs a loop.
    std::vector<char> reads_prepared(nf, 0), has_loop(nf, 0), walked(nf, 0);
    std::function<void(int)> walk = [&](int fn) {
        if (walked[size_t(fn)]) return;
        walked[size_t(fn)] = 1;
        for (const Instr& in : m.functions[size_t(fn)].body) {
            if (in.op == Op::Global && m.globals[size_t(in.aux)].kind == Global::Kind::Prepared) reads_prepared[size_t(fn)] = 1;
            if (in.op == Op::Call || in.op == Op::Loop) {
                walk(in.aux);
                reads_prepared[size_t(fn)] |= reads_prepared[size_t(in.aux)];
                has_loop[size_t(fn)] |= in.op == Op::Loop || has_loop[size_t(in.aux)];
            }
        }
    };
    for (size_t fi = 0; fi < nf; ++fi) walk(int(fi));
    // Parameters every call passes the same global or constant: found from below (none known), a round per
    // level of calls (the IR has no recursion).
    Sources sources(nf);
    for (size_t fi = 0; fi < nf; ++fi) sources[fi].assign(m.functions[fi].params.size(), std::nullopt);
    std::vector<std::vector<std::pair<int, ValueId>>> callers(nf);
    for (size_t fi = 0; fi < nf; ++fi)
        for (size_t i = 0; i < m.functions[fi].body.size(); ++i)
            if (m.functions[fi].body[i].op == Op::Call) callers[size_t(m.functions[fi].body[i].aux)].push_back({int(fi), ValueId(i)});
    for (bool changed = true; changed;) {
        changed = false;
        for (size_t fi = 0; fi < nf; ++fi) {
            const Function& f = m.functions[fi];
            if (f.entry || body[fi] || callers[fi].empty()) continue;
            for (size_t k = 0; k < f.params.size(); ++k) {
                if (sources[fi][k]) continue;
                std::optional<Source> same;
                bool ok = true;
                for (auto [ci, call] : callers[fi]) {
                    const Function& c = m.functions[size_t(ci)];
                    auto s = body[size_t(ci)] ? std::nullopt : source_of(m, c, c.body[call].args[k], sources[size_t(ci)]);
                    if (!s || (same && !(*same == *s))) {
                        ok = false;
                        break;
                    }
                    same = s;
                }
                if (ok && same) sources[fi][k] = same, changed = true;
            }
        }
    }

    Function made;  // what iqc_prepare computes besides what it did
    if (prep >= 0) made = m.functions[size_t(prep)];
    else {
        made.name = names::kPrepare;
        made.glsl_name = names::kPrepare;
    }
    const size_t prep_outputs = made.outputs.size();
    // Hash-consing of what is copied into iqc_prepare: identical values of several functions are one value there
    // (and one global).
    std::map<std::tuple<int, int, std::string, std::vector<double>, std::vector<ValueId>>, ValueId> consed;
    std::map<ValueId, int> global_of;  // a value of iqc_prepare -> the prepared global holding it
    int hoisted = 0, components = 0;
    std::vector<Global> new_globals;
    for (size_t fi = 0; fi < nf; ++fi) {
        if (body[fi] || prepares[fi] || !marched[fi]) continue;
        Function& f = m.functions[fi];
        const size_t n = f.body.size();
        std::vector<char> inv(n, 0), loops(n, 0), used_variant(n, 0);
        for (size_t i = 0; i < n; ++i) {
            const Instr& in = f.body[i];
            switch (in.op) {
                case Op::Const: case Op::Input: inv[i] = 1; break;
                case Op::Global: inv[i] = m.globals[size_t(in.aux)].kind != Global::Kind::Prepared; break;
                case Op::Param: inv[i] = size_t(in.aux) < sources[fi].size() && sources[fi][size_t(in.aux)].has_value(); break;
                case Op::Call:  // a function of invariant arguments that reads no prepared global (a local function's ∑)
                    inv[i] = !reads_prepared[size_t(in.aux)];
                    for (ValueId a : in.args) inv[i] &= inv[a];
                    break;
                default:
                    inv[i] = 1;
                    for (ValueId a : in.args) inv[i] &= inv[a];
            }
            loops[i] = in.op == Op::Loop || (in.op == Op::Call && has_loop[size_t(in.aux)]);
            for (ValueId a : in.args) loops[i] |= loops[a];
        }
        used_variant[f.result] = 1;
        // What the function's result needs: its other outputs (named values) are no caller's (a call gives its
        // result): a material's ambient copy, called with P_L = 0, kept a sum of the light term that nothing read.
        std::vector<char> needed(n, 0);
        needed[f.result] = 1;
        for (size_t i = n; i-- > 0;)
            if (needed[i])
                for (ValueId a : f.body[i].args) {
                    needed[a] = 1;
                    if (!inv[i]) used_variant[a] = 1;
                }
        // The values to hoist: invariant, holding a loop, used by what is not; of a type a global can hold (else
        // their operands).
        std::vector<ValueId> chosen;
        std::vector<char> seen(n, 0);
        std::function<void(ValueId)> choose = [&](ValueId v) {
            if (seen[v] || !inv[v] || !loops[v]) return;
            seen[v] = 1;
            const Instr& in = f.body[v];
            if (hoistable_type(in.type) && in.op != Op::Loop) chosen.push_back(v);
            else
                for (ValueId a : in.args) choose(a);
        };
        for (size_t i = 0; i < n; ++i)
            if (used_variant[i] && inv[i] && loops[i]) choose(ValueId(i));
        if (chosen.empty()) continue;
        // Copied into iqc_prepare, parameters as what every call passes.
        std::unordered_map<ValueId, ValueId> copied;
        std::function<ValueId(ValueId)> copy = [&](ValueId v) -> ValueId {
            if (auto it = copied.find(v); it != copied.end()) return it->second;
            const Instr& in = f.body[v];
            Instr c = in;
            if (in.op == Op::Param) {
                const Source& s = *sources[fi][size_t(in.aux)];
                c = Instr{};
                c.op = s.op;
                c.type = s.type;
                c.aux = s.aux;
                c.data = s.data;
            } else {
                for (ValueId& a : c.args) a = copy(a);
            }
            auto key = std::make_tuple(int(c.op), c.aux, c.type.str(), c.data, c.args);
            auto it = consed.find(key);
            ValueId out = it != consed.end() ? it->second : made.add(std::move(c));
            consed.emplace(key, out);
            return copied[v] = out;
        };
        for (ValueId v : chosen) {
            ValueId pv = copy(v);
            int g;
            if (auto it = global_of.find(pv); it != global_of.end()) g = it->second;
            else {
                // Past the cap, computed where it was (its copy in iqc_prepare is dead code).
                if (components + f.body[v].type.components() > kMaxComponents) continue;
                components += f.body[v].type.components();
                const Instr& in = f.body[v];
                std::string base = "pixel_" + (in.name.empty() ? std::string("value") : in.name);
                std::string name = base;
                for (int k = 2; m.find_global(name) >= 0 || std::any_of(new_globals.begin(), new_globals.end(),
                                                                          [&](const Global& x) { return x.name == name; });
                     ++k)
                    name = fmt::format("{}_{}", base, k);
                Global gl;
                gl.name = name;
                gl.type = in.type;
                gl.kind = Global::Kind::Prepared;
                gl.bounds.input = true;
                gl.comment = "computed once per pixel" + (in.source.empty() ? std::string() : ": " + in.source);
                g = int(m.globals.size() + new_globals.size());
                new_globals.push_back(std::move(gl));
                global_of[pv] = g;
                made.outputs.push_back({name, pv});
            }
            Instr& in = f.body[v];
            in.op = Op::Global;
            in.aux = g;
            in.args.clear();
            in.data.clear();
            ++hoisted;
        }
    }
    if (!hoisted) return 0;
    for (auto& g : new_globals) m.globals.push_back(std::move(g));
    if (prep_outputs == 0) made.result = made.outputs[0].second;
    eliminate_dead_code(made);  // (the copies of values past the cap)
    if (prep >= 0) m.functions[size_t(prep)] = std::move(made);
    else m.functions.push_back(std::move(made));
    return hoisted;
}

}  // namespace iqc::ir
