// Probe shaders: a module's outputs computed by emitted GLSL and written to pixels, so tests can compare
// the GLSL backend with the double-precision evaluator on the same IR (every construct of the language,
// through a real GLSL compiler and GPU or llvmpipe).
//
// Output j's components (row-major for matrices) go to consecutive pixels of the bottom row, red channel,
// starting at `first_pixel`. Outputs GLSL cannot hold (larger than vec4/mat4, row vectors) are listed with
// first_pixel = -1.
#pragma once

#include <string>
#include <vector>

#include "ir/Eval.h"
#include "ir/IR.h"
#include "source/Source.h"

namespace iqc::glsl {

struct ProbeOutput {
    std::string name;
    Type type;
    int first_pixel = -1;
};

struct Probe {
    std::string code;  // a Shadertoy program (mainImage)
    std::vector<ProbeOutput> outputs;
    int pixels = 0;    // width of the image to render (height 1)
};

Probe make_probe(const ir::Module& m, int fn, const std::vector<ir::Value>& args, Diagnostics& d);

}  // namespace iqc::glsl
