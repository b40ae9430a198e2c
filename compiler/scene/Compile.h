// Scene compilation, one way through:
//   scene -> instance plans (scene/Plan.h: modules checked, overrides applied, transforms evaluated)
//   -> the scene's IR (scene/SceneLower.h: modules and the scene itself as functions and globals)
//   -> the pass pipeline (ir/Pipeline.h) -> the scene backend (scene/Backend.h: storage per target, GLSL)
//   -> the runtime template (runtime_templates/scene.glsl) -> glslang validation.
// The optimized IR is also the double-precision reference (SceneModel).
//
// Module lookup for `type = "torus"`: modules of the scene or its document, then included files, then the
// standard library (stdlib/, embedded in the binary); the same name in the scene and an include is an
// error naming both. Transforms known at compile time are evaluated in double precision and inverted once;
// a transform that scales divides the distance by its Lipschitz factor so sphere tracing stays conservative.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "scene/Backend.h"
#include "scene/Reference.h"
#include "scene/Scene.h"

namespace iqc {

// Shadertoy: mainImage, parameters as constants. WebGL2 (GLSL ES 3.00), GLSL330 (desktop core): uniforms, the
// camera as uniforms, gl_FragDepth. SPIRV: Vulkan GLSL 4.50 (uniform blocks at set 0) compiled to SPIR-V and
// validated; HLSL: that SPIR-V cross-compiled to Shader Model 5.0 and re-checked; WGSL: that SPIR-V
// translated to WebGPU's shading language (glsl/Wgsl.h).
// ThreeJS: the WebGL2 shader without uniform blocks (per-instance data in the data texture), for three.js.
enum class Target { Shadertoy, WebGL2, GLSL330, SPIRV, HLSL, ThreeJS, WGSL };

const char* target_name(Target t);

// The targets built from the Vulkan GLSL's SPIR-V (one layout: blocks at set 0, `--meta` "inputs_block").
inline bool through_spirv(Target t) { return t == Target::SPIRV || t == Target::HLSL || t == Target::WGSL; }

struct CompileOptions {
    Target target = Target::Shadertoy;
    bool dump_ir = false;
    std::string dump_after;    // a pass name: the IR after that pass (--dump-ir=after-NAME); "" is after the last
    std::string inject_fault;  // tests of the internal-error path: a pass name, or "glslang" (an invalid shader)
#ifdef NDEBUG
    bool verify_each = false;  // verify the IR before and after every pass (tests, debug builds)
#else
    bool verify_each = true;
#endif
    // Instrumented build: each pixel is (march steps of the camera ray, scene evaluations, NaN flag, 1)
    // instead of a colour (for `iqc render --stats` and `iqc bench`).
    bool instrument = false;
    // Geometry probe: each pixel is (distance along the camera ray or -1, unit normal) (tests).
    bool geometry = false;
    // Instance probe: each pixel is (distance along the camera ray or -1, the hit instance's id or -1) (tests).
    bool ids = false;
    // Range-analysis warnings (a slider can push an operation out of its domain) become errors.
    bool strict_ranges = false;
    // Overrides of [render] for benchmark sweeps (unset: the scene's own values).
    std::optional<March> march;
    std::optional<Normals> normals;
    std::optional<double> hit;
    std::optional<int> max_steps;
    // Benchmark baseline: I♥IQ's architecture (one march per instance, transforms inverted per instance).
    bool per_instance = false;
    // Benchmark floor (`oracle` in `iqc bench`): the fewest scene evaluations any march whose steps are
    // certified by overlapping unbounding spheres (sphere tracing, over-relaxation, auto-relaxation) can take
    // on each ray; it searches with evaluations it does not count (docs/accuracy.md). Sphere tracing's
    // settings otherwise.
    bool oracle = false;
    // Benchmark build: the hit tolerance, the step cap and the output (colour, counts, geometry) are
    // uniforms (IQC_HIT, IQC_MAX_STEPS, iqc_mode), so one program serves a whole sweep.
    bool bench = false;
    double bench_max_hit = 0;  // `bench`: the largest hit tolerance the build will be given (the scene box covers it)
};

struct CompileResult {
    int exit_code = 1;     // 0 ok, 1 diagnostics about the input, 3 internal error (glslang rejected our output)
    std::string code;      // the shader (only when exit_code == 0): for SPIRV the Vulkan GLSL it was compiled from
    std::vector<uint32_t> spirv;  // SPIRV and HLSL targets: the validated SPIR-V module
    std::string ir;        // the IR, when dump_ir
    // Per scene item, the Lipschitz bound applied to its distance: "dtorus (dtorus_1_distance): K ≤ 8.689
    // derived, 4.906 sampled, 8.689 applied (derived)" (ir/passes/Lipschitz.h).
    std::vector<std::string> lipschitz;
    std::string internal;  // the internal error's text (exit code 3)
    std::string meta;      // JSON describing every parameter (instance, module, role, uniform, bounds, ...)
    std::vector<std::pair<std::string, double>> pass_ms;  // wall time per phase, for --time-passes
    std::shared_ptr<const SceneModel> model;  // the scene in double precision (when the compile succeeded)
    bool blends = false;                      // the scene has [[blends]] (I♥IQ's per-instance march cannot draw them)
    // webgl2/glsl330: what a host sets before drawing (every uniform's default, uniform blocks, data texture).
    ShaderInputs inputs;
};

CompileResult compile_scene(const SceneDesc& scene, SourceManager& sm, Diagnostics& diags, const CompileOptions& opts);

// Convenience: load + compile a file.
CompileResult compile_file(const std::string& path, SourceManager& sm, Diagnostics& diags, const CompileOptions& opts);

}  // namespace iqc
