// PNG input/output for render::Image (libpng).
//
// write_png stores 8 bits per channel: each value is clamped to [0, 1] and rounded (x * 255 + 0.5).
// A pixel whose R, G or B is NaN is written as opaque magenta (255, 0, 255) so NaNs stand out. The
// output is deterministic (no timestamp or other metadata chunks): same image, same bytes.
//
// read_png accepts any PNG (8-bit RGB/RGBA are the expected case; palette, grey and 16-bit images are
// converted) and returns floats = byte / 255, with alpha = 1 where the file has none.
#pragma once

#include "render/Render.h"

#include <string>

namespace iqc::render {

// Writes `img` to `path`. By default an RGB PNG (alpha dropped, as Shadertoy's canvas shows it);
// with keep_alpha = true an RGBA PNG. Returns false and sets *error (if non-null) on failure, in which
// case no partial file is left behind.
bool write_png(const std::string& path, const Image& img, std::string* error, bool keep_alpha = false);

// Reads `path` into `out` (top row first). Returns false and sets *error (if non-null) on failure;
// `out` is left unchanged then.
bool read_png(const std::string& path, Image& out, std::string* error);

}  // namespace iqc::render
