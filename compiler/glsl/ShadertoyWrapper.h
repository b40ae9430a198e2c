// The text Shadertoy puts around a pasted shader, reproduced so that iqc can validate (glslang) and
// render (EGL) exactly what a user pastes into shadertoy.com/new.
//
// Shadertoy compiles the user's code as GLSL ES 3.00 with this prelude (its uniforms) and a `main` that
// calls `mainImage(out vec4 fragColor, in vec2 fragCoord)`. iqc's Shadertoy output uses nothing else.
#pragma once

#include <string>
#include <string_view>

namespace iqc::glsl {

// The uniforms Shadertoy declares. Any renderer that runs a Shadertoy shader sets these.
inline constexpr std::string_view kShadertoyPrelude =
    "#version 300 es\n"
    "precision highp float;\n"
    "precision highp int;\n"
    "precision mediump sampler3D;\n"
    "uniform vec3 iResolution;\n"
    "uniform float iTime;\n"
    "uniform float iTimeDelta;\n"
    "uniform float iFrameRate;\n"
    "uniform int iFrame;\n"
    "uniform float iChannelTime[4];\n"
    "uniform vec3 iChannelResolution[4];\n"
    "uniform vec4 iMouse;\n"
    "uniform vec4 iDate;\n"
    "uniform float iSampleRate;\n"
    "uniform sampler2D iChannel0;\n"
    "uniform sampler2D iChannel1;\n"
    "uniform sampler2D iChannel2;\n"
    "uniform sampler2D iChannel3;\n"
    "out vec4 iqc_FragColor;\n";

inline constexpr std::string_view kShadertoyEpilogue =
    "\nvoid main() {\n"
    "    vec4 color = vec4(0.0, 0.0, 0.0, 1.0);\n"
    "    mainImage(color, gl_FragCoord.xy);\n"
    "    iqc_FragColor = color;\n"
    "}\n";

// Number of lines the prelude adds before the user's first line (for mapping glslang's line numbers back).
inline int shadertoy_prelude_lines() {
    int n = 0;
    for (char c : kShadertoyPrelude) n += (c == '\n');
    return n;
}

// The complete fragment shader Shadertoy would compile for `user_code`.
inline std::string wrap_shadertoy(std::string_view user_code) {
    std::string s;
    s.reserve(kShadertoyPrelude.size() + user_code.size() + kShadertoyEpilogue.size() + 1);
    s += kShadertoyPrelude;
    s += user_code;
    if (!user_code.empty() && user_code.back() != '\n') s += '\n';
    s += kShadertoyEpilogue;
    return s;
}

}  // namespace iqc::glsl
