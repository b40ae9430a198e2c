// Reads the IR's text form (ir::print) back into a module, for pass tests written in IR text: input IR,
// one pass, compare the printed result (as Tint's and Halide's pass tests do).
//
// Everything print() writes is read back: globals (kind, value, bounds), function flags, parameters with
// bounds, instructions with their operation-specific parts, results and outputs. Statement sources and
// spans are not part of the text. Comments run from `;` to the end of a line (except the `; name` that
// names an instruction); blank lines are ignored.
#pragma once

#include <string>

#include "ir/IR.h"

namespace iqc::ir {

// Parses `text`; on failure returns false and sets `error` to "line N: what".
bool parse_module(const std::string& text, Module& out, std::string& error);

}  // namespace iqc::ir
