// PNG input/output for render::Image with libpng (see Png.h).
//
// libpng reports errors by longjmp. To keep that well defined in C++, every function that calls
// setjmp below holds no C++ objects with destructors and modifies no automatic variables after the
// setjmp; all std::vector/std::string work happens in the callers, before or after.
#include "render/Png.h"

#include <png.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>
#include <vector>

namespace iqc::render {
namespace {

// Receives libpng's error message (libpng's error callback must not return; it longjmps).
struct PngErrorSink {
    char message[256] = "unknown libpng error";
};

void on_png_error(png_structp png, png_const_charp msg) {
    auto* sink = static_cast<PngErrorSink*>(png_get_error_ptr(png));
    if (sink) std::snprintf(sink->message, sizeof sink->message, "%s", msg ? msg : "unknown libpng error");
    png_longjmp(png, 1);
}

void on_png_warning(png_structp, png_const_charp) {}  // warnings are not interesting here

void set_error(std::string* error, const std::string& message) {
    if (error) *error = message;
}

// Float channel value -> 8 bits: clamp to [0, 1], round to nearest.
png_byte to_byte(float v) {
    if (!(v > 0.0f)) return 0;  // also catches NaN (handled per pixel by the caller)
    if (v >= 1.0f) return 255;
    return static_cast<png_byte>(v * 255.0f + 0.5f);
}

// Writes already-converted 8-bit rows. No C++ objects live in this frame (see the file comment).
bool write_rows(FILE* file, png_uint_32 width, png_uint_32 height, int color_type, png_bytep* rows,
                PngErrorSink* sink) {
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, sink, on_png_error, on_png_warning);
    if (!png) return false;
    png_infop info = png_create_info_struct(png);
    if (!info) {
        png_destroy_write_struct(&png, nullptr);
        return false;
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        return false;
    }
    png_init_io(png, file);
    png_set_IHDR(png, info, width, height, 8, color_type, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                 PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_write_image(png, rows);
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    return true;
}

// A libpng read in two steps (header, then pixels), each with its own setjmp; the libpng structures
// live in this object, not in the setjmp frames. The FILE is owned by the caller.
class PngReader {
public:
    explicit PngReader(PngErrorSink* sink) {
        png_ = png_create_read_struct(PNG_LIBPNG_VER_STRING, sink, on_png_error, on_png_warning);
        if (png_) info_ = png_create_info_struct(png_);
    }
    ~PngReader() {
        if (png_) png_destroy_read_struct(&png_, info_ ? &info_ : nullptr, nullptr);
    }
    PngReader(const PngReader&) = delete;
    PngReader& operator=(const PngReader&) = delete;

    bool valid() const { return png_ && info_; }

    // Reads the header (after the 8 signature bytes already consumed from `file`) and sets up the
    // transformations to 8-bit RGBA. On success *width, *height and *row_bytes describe the output.
    bool read_header(FILE* file, png_uint_32* width, png_uint_32* height, size_t* row_bytes) {
        if (setjmp(png_jmpbuf(png_))) return false;
        png_init_io(png_, file);
        png_set_sig_bytes(png_, 8);
        png_read_info(png_, info_);
        const int color_type = png_get_color_type(png_, info_);
        const int bit_depth = png_get_bit_depth(png_, info_);
        if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png_);
        if (color_type == PNG_COLOR_TYPE_GRAY && bit_depth < 8) png_set_expand_gray_1_2_4_to_8(png_);
        if (png_get_valid(png_, info_, PNG_INFO_tRNS)) png_set_tRNS_to_alpha(png_);
        if (bit_depth == 16) png_set_scale_16(png_);
        if (color_type == PNG_COLOR_TYPE_GRAY || color_type == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_gray_to_rgb(png_);
        if (!(color_type & PNG_COLOR_MASK_ALPHA) && !png_get_valid(png_, info_, PNG_INFO_tRNS))
            png_set_add_alpha(png_, 0xFF, PNG_FILLER_AFTER);
        png_set_interlace_handling(png_);
        png_read_update_info(png_, info_);
        *width = png_get_image_width(png_, info_);
        *height = png_get_image_height(png_, info_);
        *row_bytes = png_get_rowbytes(png_, info_);
        return true;
    }

    // Reads all rows (top first) into the given row pointers.
    bool read_pixels(png_bytep* rows) {
        if (setjmp(png_jmpbuf(png_))) return false;
        png_read_image(png_, rows);
        png_read_end(png_, nullptr);
        return true;
    }

private:
    png_structp png_ = nullptr;
    png_infop info_ = nullptr;
};

// Closes a FILE on scope exit.
struct FileCloser {
    FILE* f;
    ~FileCloser() {
        if (f) std::fclose(f);
    }
};

}  // namespace

bool write_png(const std::string& path, const Image& img, std::string* error, bool keep_alpha) {
    if (img.width <= 0 || img.height <= 0 ||
        img.rgba.size() != static_cast<size_t>(img.width) * static_cast<size_t>(img.height) * 4) {
        set_error(error, "write_png: invalid image (" + std::to_string(img.width) + "x" +
                             std::to_string(img.height) + ", " + std::to_string(img.rgba.size()) + " floats)");
        return false;
    }

    // Convert to 8-bit rows.
    const int channels = keep_alpha ? 4 : 3;
    const size_t row_bytes = static_cast<size_t>(img.width) * channels;
    std::vector<png_byte> bytes(row_bytes * static_cast<size_t>(img.height));
    std::vector<png_bytep> rows(static_cast<size_t>(img.height));
    for (int y = 0; y < img.height; ++y) {
        png_bytep row = bytes.data() + static_cast<size_t>(y) * row_bytes;
        rows[static_cast<size_t>(y)] = row;
        for (int x = 0; x < img.width; ++x) {
            const float* p = img.pixel(x, y);
            png_bytep out = row + static_cast<size_t>(x) * channels;
            if (std::isnan(p[0]) || std::isnan(p[1]) || std::isnan(p[2])) {
                out[0] = 255, out[1] = 0, out[2] = 255;  // NaN: magenta
                if (keep_alpha) out[3] = 255;
                continue;
            }
            for (int c = 0; c < 3; ++c) out[c] = to_byte(p[c]);
            if (keep_alpha) out[3] = std::isnan(p[3]) ? 255 : to_byte(p[3]);
        }
    }

    FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) {
        set_error(error, "write_png: cannot open '" + path + "' for writing: " + std::strerror(errno));
        return false;
    }
    PngErrorSink sink;
    const int color_type = keep_alpha ? PNG_COLOR_TYPE_RGB_ALPHA : PNG_COLOR_TYPE_RGB;
    bool ok = write_rows(file, static_cast<png_uint_32>(img.width), static_cast<png_uint_32>(img.height), color_type,
                         rows.data(), &sink);
    std::string why = ok ? "" : std::string("libpng: ") + sink.message;
    if (std::fclose(file) != 0 && ok) {
        ok = false;
        why = std::string("close failed: ") + std::strerror(errno);
    }
    if (!ok) {
        std::remove(path.c_str());
        set_error(error, "write_png: cannot write '" + path + "': " + why);
    }
    return ok;
}

bool read_png(const std::string& path, Image& out, std::string* error) {
    FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) {
        set_error(error, "read_png: cannot open '" + path + "': " + std::strerror(errno));
        return false;
    }
    FileCloser closer{file};

    png_byte signature[8];
    if (std::fread(signature, 1, 8, file) != 8 || png_sig_cmp(signature, 0, 8) != 0) {
        set_error(error, "read_png: '" + path + "' is not a PNG file");
        return false;
    }

    PngErrorSink sink;
    PngReader reader(&sink);
    if (!reader.valid()) {
        set_error(error, "read_png: libpng initialisation failed");
        return false;
    }
    png_uint_32 width = 0, height = 0;
    size_t row_bytes = 0;
    if (!reader.read_header(file, &width, &height, &row_bytes)) {
        set_error(error, "read_png: '" + path + "': libpng: " + sink.message);
        return false;
    }
    if (width == 0 || height == 0 || row_bytes != static_cast<size_t>(width) * 4) {
        set_error(error, "read_png: '" + path + "': unexpected layout after conversion to RGBA8");
        return false;
    }

    std::vector<png_byte> bytes(row_bytes * height);
    std::vector<png_bytep> rows(height);
    for (png_uint_32 y = 0; y < height; ++y) rows[y] = bytes.data() + static_cast<size_t>(y) * row_bytes;
    if (!reader.read_pixels(rows.data())) {
        set_error(error, "read_png: '" + path + "': libpng: " + sink.message);
        return false;
    }

    Image img;
    img.width = static_cast<int>(width);
    img.height = static_cast<int>(height);
    img.rgba.resize(bytes.size());
    for (size_t i = 0; i < bytes.size(); ++i) img.rgba[i] = bytes[i] / 255.0f;
    out = std::move(img);
    return true;
}

}  // namespace iqc::render
