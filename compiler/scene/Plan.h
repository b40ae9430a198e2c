// Instance planning: every `[[shapes]]` entry resolved against the module library — its name, its shape and
// material modules (checked), the values of their parameters after the scene's overrides, the roles the
// renderer binds (from the checker: CheckedModule::roles), and its transform: checked, evaluated at its
// parameters' values in double precision, inverted once, and known to be affine and invertible.
//
// Errors are located diagnostics (unknown module with did-you-mean, a parameter that does not exist or has
// the wrong size, two instances with one name, a singular or non-affine transform, ...).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "ir/IR.h"
#include "scene/Modules.h"
#include "scene/Scene.h"

namespace iqc {

// The renderer's conventions for material parameters (docs/scene.md).
namespace conventions {
inline constexpr const char* kLightPosition = "P_L";
inline constexpr const char* kLightColor = "C_L";
inline constexpr const char* kAmbientColor = "C_A";  // indirect light: the scene's sky and bounce lights
// The pixel's footprint at the surface point: the width, along each world axis, of the box that the cone of one
// pixel (one antialiasing sample) covers on the surface there (ℝ³, world units), for filtering patterns.
inline constexpr const char* kFootprint = "w_P";
inline constexpr const char* kReflectivity = "k_r";
inline constexpr const char* kTransmission = "k_t";
inline constexpr const char* kRefractiveIndex = "η";
inline constexpr const char* kRefractiveIndexAscii = "eta";
}  // namespace conventions

struct InstancePlan {
    const InstanceDesc* desc = nullptr;
    std::string name;  // as the user sees it: explicit, or `<type>_<n>`
    const CheckedModule* shape = nullptr;
    int query = -1;    // the shape's query-point parameter
    std::vector<std::vector<double>> shape_values;     // per shape parameter
    const CheckedModule* material = nullptr;           // null: the default material (normal colour)
    std::vector<std::vector<double>> material_values;  // per material parameter
    // The transform (when there is one and it is not blank).
    std::shared_ptr<CheckedModule> transform;
    std::vector<double> inv_linear{1, 0, 0, 0, 1, 0, 0, 0, 1};  // world -> object at the parameters' values, row-major
    std::vector<double> inv_offset{0, 0, 0};
    double scale = 1;                    // 1 / Lipschitz factor of the world -> object map
    // How much shorter than the distance to the surface sphere tracing's steps near this instance may be, from
    // its transform alone: the world → object map's condition number ‖M‖‖M⁻¹‖ at the parameters' values (a
    // non-uniform scale: the distance is multiplied by 1/‖M‖, exact only along the most stretched axis).
    double step_shortening = 1;
    std::string transform_comment;       // the transform as written, one line, with its parameters' values
    bool has_transform = false;
    int blend = -1;                      // the [[blends]] entry it is part of, or -1
    bool transform_uses_inputs = false;  // reads `time` or `mouse`

    // The material parameters the scene's lights bind (ℝ³ each): P_L and C_L when it has point lights or suns
    // (`shading`), C_A when it has sky or bounce lights (`ambient`).
    bool lit_by(int param, bool shading, bool ambient = false) const;
    bool per_light(bool shading) const;  // the material's light terms are evaluated once per light
    bool binds_footprint() const;        // the material has the footprint parameter w_P ∈ ℝ³ (the renderer sets it)
};

// Plans every instance of the scene (and resolves [[blends]] to them); returns false after reporting errors.
// strict_ranges (--strict-ranges): a parameter value outside its slider bounds is an error, not a warning.
bool plan_instances(const SceneDesc& scene, ModuleLibrary& lib, SourceManager& sm, Diagnostics& d,
                    std::vector<InstancePlan>& plans, bool strict_ranges = false);

}  // namespace iqc
