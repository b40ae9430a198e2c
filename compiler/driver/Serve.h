// `iqc serve`: the html page of a scene on 127.0.0.1 only, recompiled when the scene or any file it reads
// changes; the page polls /version and reloads (its sliders keep their values). A compile error becomes a
// page that shows the diagnostics. Only "/" and "/version" exist: every other path is 404.
#pragma once

#include <string>

namespace iqc {

// Serves until interrupted. port 0 picks a free port. Returns the exit code.
int serve(const std::string& input, int port, double poll_seconds);

}  // namespace iqc
