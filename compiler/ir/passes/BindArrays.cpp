#include "ir/passes/BindArrays.h"

#include <map>
#include <utility>

namespace iqc::ir {

// On targets whose parameters are constants, arrays of this many elements or more are bound.
constexpr int kBoundConstantArray = 64;

int bind_array_arguments(Module& m) {
    // (callee, the global bound to each argument or -1) -> the copy
    std::map<std::pair<int, std::vector<int>>, int> copies;
    int rebound = 0;
    // Copies are appended and visited in turn: a copy that passes its global on is bound again (IR has no
    // recursion, so this ends).
    for (size_t fi = 0; fi < m.functions.size(); ++fi) {
        for (size_t i = 0; i < m.functions[fi].body.size(); ++i) {
            const Instr& in = m.functions[fi].body[i];
            if (in.op != Op::Call && in.op != Op::Loop) continue;
            // A call's arguments are its callee's parameters; a loop's are its bound, initial states and
            // captures, its body's parameters the index, the states and the captures: only captures bind.
            const size_t first = in.op == Op::Loop ? 1 + m.functions[size_t(in.aux)].outputs.size() : 0;
            std::vector<int> bound(in.args.size(), -1);
            bool any = false;
            for (size_t a = first; a < in.args.size(); ++a) {
                const Instr& x = m.functions[fi].body[in.args[a]];
                if (x.op != Op::Global || !x.type.is_array()) continue;
                if (m.globals[size_t(x.aux)].kind != Global::Kind::Parameter) continue;
                // Constants (Shadertoy): only long arrays, whose copies Mesa's compile chokes on (three
                // instances' `const vec3 x[1100]` passed by value six times: no first frame in 120 s); the driver
                // folds a short one's values into the code.
                if (m.constant_parameters && x.type.count < kBoundConstantArray) continue;
                bound[a] = x.aux;
                any = true;
            }
            if (!any) continue;
            const int callee = in.aux;
            auto key = std::make_pair(callee, bound);
            auto it = copies.find(key);
            if (it == copies.end()) {
                Function c = m.functions[size_t(callee)];
                std::string which;
                for (int g : bound)
                    if (g >= 0) which += "." + m.globals[size_t(g)].name;
                c.name += which;
                if (c.glsl_name.empty()) c.glsl_name = m.functions[size_t(callee)].name;
                c.entry = false;
                c.inline_hint = false;
                c.lipschitz = {};
                // The kept parameters' new indices.
                std::vector<int> renumber(bound.size(), -1);
                std::vector<FunctionParam> params;
                std::vector<ValueBounds> param_bounds;
                for (size_t a = 0; a < bound.size(); ++a) {
                    if (bound[a] >= 0) continue;
                    renumber[a] = int(params.size());
                    params.push_back(c.params[a]);
                    if (a < c.param_bounds.size()) param_bounds.push_back(c.param_bounds[a]);
                }
                for (Instr& x : c.body) {
                    if (x.op != Op::Param) continue;
                    const size_t a = size_t(x.aux);
                    if (bound[a] >= 0) {
                        x.op = Op::Global;
                        x.aux = bound[a];
                    } else {
                        x.aux = renumber[a];
                    }
                }
                c.params = std::move(params);
                if (!c.param_bounds.empty()) c.param_bounds = std::move(param_bounds);
                m.functions.push_back(std::move(c));
                it = copies.emplace(key, int(m.functions.size() - 1)).first;
            }
            Instr& call = m.functions[fi].body[i];
            std::vector<ValueId> args;
            for (size_t a = 0; a < call.args.size(); ++a)
                if (bound[a] < 0) args.push_back(call.args[a]);
            // (a loop's body keeps its index at parameter 0: bound[0] is never set for a loop, so the kept
            // parameters keep their order and the loop's arguments their meaning)
            call.args = std::move(args);
            call.aux = it->second;
            ++rebound;
        }
    }
    return rebound;
}

}  // namespace iqc::ir
