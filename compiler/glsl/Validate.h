// glslang validation of every shader iqc writes. A shader glslang rejects is a bug in iqc, never the
// user's fault: the driver reports it with exit code 3 and writes nothing.
#pragma once

#include <string>

namespace iqc::glsl {

enum class Profile { Es300, Core330 };

struct ValidationResult {
    bool ok = false;
    std::string log;  // glslang's messages when not ok
};

// Compiles and links `source` (a complete fragment shader with its #version line).
ValidationResult validate_fragment(const std::string& source, Profile profile);

}  // namespace iqc::glsl
