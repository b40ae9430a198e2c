#include "ir/passes/CSE.h"

#include <bit>
#include <cstdint>
#include <map>
#include <tuple>

namespace iqc::ir {

int eliminate_common_subexpressions(Function& f) {
    // Constants compare by their bits: NaN is not ordered (a std::map keyed on it merges unrelated
    // constants), and -0 is not 0 (1/-0 = -∞).
    using Key = std::tuple<int, Type, int, std::vector<ValueId>, std::vector<uint64_t>>;
    std::map<Key, ValueId> seen;
    std::vector<ValueId> remap(f.body.size());
    int redirected = 0;
    for (size_t i = 0; i < f.body.size(); ++i) {
        Instr& in = f.body[i];
        remap[i] = ValueId(i);
        for (ValueId& a : in.args) a = remap[a];
        if (in.op == Op::Param || in.op == Op::Copy) continue;
        std::vector<uint64_t> bits(in.data.size());
        for (size_t c = 0; c < in.data.size(); ++c) bits[c] = std::bit_cast<uint64_t>(in.data[c]);
        Key k{int(in.op), in.type, in.aux, in.args, std::move(bits)};
        auto it = seen.find(k);
        if (it == seen.end()) {
            seen.emplace(std::move(k), ValueId(i));
            continue;
        }
        if (in.name.empty()) {
            remap[i] = it->second;
            ++redirected;
        } else if (f.body[it->second].name.empty()) {
            it->second = ValueId(i);  // later copies use the named value
        }
    }
    f.result = remap[f.result];
    for (auto& [name, v] : f.outputs) v = remap[v];
    return redirected;
}

}  // namespace iqc::ir
