// The `cpp` target: a C++17 header holding the webgl2 shader (GLSL ES 3.00, already validated) as a
// constant and a constexpr table of its parameters, for engines that compile shaders into the binary.
//
//     namespace iqc_<stem> {
//     inline constexpr std::string_view kFragmentShader = ...;       // the webgl2 target's text
//     struct Parameter { instance, module, role, name, storage, location, type; components; defaults[16];
//                        lo[16], hi[16] (unbounded: -inf/+inf); block; offsets[16] (bytes in the block,
//                        floats in the data texture, -1 for a plain uniform) };
//     inline constexpr std::array<Parameter, N> kParameters = {...};
//     struct Block { name; binding; bytes; data_base64; };  inline constexpr std::array<Block, M> kBlocks;
//     }
//
// Every user string (names, descriptions, the title) is written as a C++ string literal with every byte
// outside printable ASCII, and '"' and '\', escaped (octal), so no input can end a literal early; the shader
// itself goes into raw string literals whose delimiter appears nowhere in it, in pieces of at most 4,000
// bytes (MSVC's limit on one literal is 16 KiB).
#pragma once

#include <string>
#include <string_view>

namespace iqc {

// `shader`: the webgl2 shader; `meta_json`: its --meta description; `stem`: the input file's stem (the
// namespace is iqc_<stem> made a C++ identifier). Throws nlohmann::json errors only on a malformed
// `meta_json` (an internal error: the compiler wrote it).
std::string cpp_header(std::string_view shader, std::string_view meta_json, std::string_view stem);

}  // namespace iqc
