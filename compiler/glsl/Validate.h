// glslang validation of every shader iqc writes. A shader glslang rejects is a bug in iqc, never the
// user's fault: the driver reports it with exit code 3 and writes nothing.
#pragma once

#include <mutex>
#include <string>

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

}  // namespace iqc::glsl
