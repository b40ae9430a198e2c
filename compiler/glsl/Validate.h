// glslang validation of every shader iqc writes. A shader glslang rejects is a bug in iqc, never the
// user's fault: the driver reports it with exit code 3 and writes nothing.
#pragma once

#include <mutex>
#include <string>

#include "source/Source.h"

namespace iqc::glsl {

enum class Profile { Es300, Core330 };

struct ValidationResult {
    bool ok = false;
    std::string log;  // glslang's messages when not ok
};

// glslang's process-wide set-up (done on the first call) and the lock every use of glslang holds.
std::mutex& glslang_mutex();

// Compiles and links `source` (a complete fragment shader with its #version line).
ValidationResult validate_fragment(const std::string& source, Profile profile);

// A GLSL compiler's log about a shader a user wrote (a .frag drawn or translated as it is), as located
// diagnostics in `file` (the shader's text, its lines counted from 1 as `#line 1` makes the driver count them):
// Mesa's `0:LINE(COL): error: message` (COL 1-based, in bytes; Mesa's column is the start of the construct it
// rejects, not always of the token) and glslang's `ERROR: NAME:LINE: message` (no column: the caret goes under
// the line's first non-blank character). Warnings stay warnings; lines of the log in neither form, and
// glslang's "compilation terminated", are left out. Returns how many errors it added (0: the caller shows the
// log as it is).
size_t locate_shader_log(const std::string& log, FileId file, Diagnostics& diags);

}  // namespace iqc::glsl
