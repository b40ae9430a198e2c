// libFuzzer harness: the front end on one module's text (lex, split names, parse, check, with the
// standard library for imports) and the rendering of its diagnostics. Any input must end normally.
#include <cstddef>
#include <cstdint>
#include <string>

#include "FuzzModule.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    iqc::fuzz::FuzzModule f(data, size);
    // A transform's text is parsed without a header and with T, R_x, ... imported (checking the imported
    // stdlib module each time is costly): one input in eight, by its first byte.
    bool transform = size > 0 && data[0] % 8 == 1;
    auto m = f.lib.parse_check(f.src, "fuzz", transform);
    std::string rendered = f.diags.render();
    return rendered.size() == size_t(-1);  // keeps the work observable
}
