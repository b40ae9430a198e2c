// `iqc eval`: evaluates a module in double precision on the IR — the graphing calculator, and the
// reference that numerical tests compare shaders against.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "ir/Eval.h"
#include "source/Source.h"

namespace iqc {

struct EvalRequest {
    std::string path;                                       // a module file (.iql), or a document/scene with `module`
    std::string module;                                     // which module of a .md/.iq (empty: the file's only one)
    std::vector<std::pair<std::string, std::string>> sets;  // NAME=VALUE, VALUE in the language's own literals
    ir::EvalInputs inputs;                                  // the reserved `time` and `mouse`
    std::vector<std::pair<std::string, double>>* timings = nullptr;  // filled with ms per phase when set
    std::string inject_fault;  // tests of the internal-error path: a pass name
};

struct EvalOutput {
    std::string name;  // as written (the bare expression is "ret")
    ir::Value value;
};

// The module runs through the same pass pipeline as a scene (ir/Pipeline.h: range guards included), so it
// means what the shader computes. Returns false (with diagnostics) when the module or a value is invalid;
// throws InternalError for a bug in iqc.
bool evaluate_module_file(const EvalRequest& req, SourceManager& sm, Diagnostics& d, std::vector<EvalOutput>& out);

}  // namespace iqc
