#include "glsl/Probe.h"

#include <fmt/format.h>

#include "glsl/Emit.h"

namespace iqc::glsl {

Probe make_probe(const ir::Module& m, int fn, const std::vector<ir::Value>& args, Diagnostics& d) {
    Probe probe;
    ir::Module ext = m;
    const ir::Function& f = m.functions[size_t(fn)];
    std::vector<int> roots;
    std::vector<std::pair<int, size_t>> probes;  // extended function index, output index
    for (size_t j = 0; j < f.outputs.size(); ++j) {
        const auto& [name, v] = f.outputs[j];
        ProbeOutput po{name, f.body[v].type, -1};
        if (!type_name(po.type).empty() && po.type.kind != Type::Bool) {
            ir::Function g = f;
            g.result = v;
            g.name = fmt::format("{}.probe{}", f.name, j);
            g.glsl_name = fmt::format("probe_{}", identifier(name));
            ext.functions.push_back(std::move(g));
            int idx = int(ext.functions.size() - 1);
            roots.push_back(idx);
            probes.push_back({idx, j});
            po.first_pixel = probe.pixels;
            probe.pixels += po.type.components();
        }
        probe.outputs.push_back(po);
    }
    Namer globals;
    Emitter em(ext, globals, d);
    std::vector<int> fns = em.closure(roots);
    for (int g : fns) em.function_name(g);
    std::string code = "// iqc probe: each output's components in consecutive pixels (red channel)\n";
    for (int g : fns) code += em.function(g) + "\n";
    std::vector<std::string> arg_text;
    for (size_t k = 0; k < args.size(); ++k) {
        const Type& pt = f.params[k].type;  // a ℤ parameter takes an int
        arg_text.push_back(constant(pt.kind == Type::Integer ? pt : args[k].type.is_scalar() ? Type::scalar() : args[k].type, args[k].v));
    }
    code += "void mainImage(out vec4 fragColor, in vec2 fragCoord) {\n    int i = int(fragCoord.x);\n    float v = 0.0;\n";
    for (auto [idx, j] : probes) {
        const ProbeOutput& po = probe.outputs[j];
        int n = po.type.components();
        code += fmt::format("    if (i >= {} && i < {}) {{\n        {} r = {}({});\n        int k = i - {};\n", po.first_pixel,
                            po.first_pixel + n, type_name(po.type), em.function_name(idx), fmt::join(arg_text, ", "),
                            po.first_pixel);
        if (po.type.is_scalar()) code += "        v = r;\n";
        else if (po.type.is_vector() || po.type.rows == 1) code += "        v = r[k];\n";
        else code += fmt::format("        v = r[k % {}][k / {}];\n", po.type.cols, po.type.cols);
        code += "    }\n";
    }
    code += "    fragColor = vec4(v, 0.0, 0.0, 1.0);\n}\n";
    probe.code = std::move(code);
    if (probe.pixels == 0) probe.pixels = 1;
    return probe;
}

}  // namespace iqc::glsl
