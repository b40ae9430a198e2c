// Internal errors: a broken invariant of the compiler itself, never a problem of the input.
//
// Passes, lowering and the evaluator throw InternalError; the entry points (compile_scene,
// evaluate_module_file) turn it into exit code 3 with "internal compiler error: … (this is a bug in iqc)".
// Problems with the input are diagnostics (source/Source.h), never exceptions.
#pragma once

#include <stdexcept>
#include <string>

namespace iqc {

struct InternalError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

[[noreturn]] inline void internal_error(const std::string& what) { throw InternalError(what); }

// The message the driver prints for an internal error (exit code 3).
inline std::string internal_error_message(const std::string& what) {
    return "internal compiler error: " + what + " (this is a bug in iqc; nothing was written)";
}

}  // namespace iqc
