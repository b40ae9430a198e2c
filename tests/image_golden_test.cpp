// Image goldens: every example rendered at 128×72 (llvmpipe) against golden/images/<name>.png, per pixel
// with a tolerance (a channel may differ by 2/255; at most 0.5% of pixels may differ more, for
// rasterisation differences between Mesa versions). A failure writes the difference image (amplified
// ×8) beside the test's temporary files and prints its path.
// Regenerate (review the pictures before committing):  IQC_UPDATE_GOLDEN=1 ./build/tests/iqc_tests "[images]"
//                                                or:  scripts/update-goldens.sh
#include <catch2/catch.hpp>

#include <cmath>

#include "TestUtil.h"
#include "glsl/ShadertoyWrapper.h"
#include "render/Png.h"
#include "render/Render.h"

using namespace iqc;
using namespace iqc::test;
namespace fs = std::filesystem;

TEST_CASE("image goldens: every example renders as its golden picture", "[images][golden][render]") {
    bool update = std::getenv("IQC_UPDATE_GOLDEN") != nullptr;
    fs::path root = IQC_SOURCE_DIR;
    std::vector<fs::path> inputs;
    for (auto& e : fs::directory_iterator(root / "examples"))
        if ((e.path().extension() == ".md" || e.path().extension() == ".iq") && e.path().filename() != "README.md")
            inputs.push_back(e.path());
    std::sort(inputs.begin(), inputs.end());
    REQUIRE(inputs.size() >= 5);
    std::string err;
    auto renderer = render::Renderer::create(&err);
    REQUIRE(renderer);
    for (const auto& in : inputs) {
        SECTION(in.filename().string()) {
            Compiled c = compile_path(in);
            REQUIRE(c.result.exit_code == 0);
            render::RenderOptions o;
            o.width = 128;
            o.height = 72;
            auto r = renderer->render(glsl::wrap_shadertoy(c.result.code), o);
            REQUIRE(r.ok);
            // Compare what a PNG holds: 8 bits per channel.
            fs::path actual_png = temp_dir() / (in.stem().string() + ".actual.png");
            REQUIRE(render::write_png(actual_png.string(), r.image, &err));
            render::Image actual;
            REQUIRE(render::read_png(actual_png.string(), actual, &err));
            fs::path golden = root / "golden" / "images" / (in.stem().string() + ".png");
            if (update) {
                fs::create_directories(golden.parent_path());
                fs::copy_file(actual_png, golden, fs::copy_options::overwrite_existing);
            }
            render::Image expected;
            INFO("golden " << golden.string() << ": " << err);
            REQUIRE(render::read_png(golden.string(), expected, &err));
            REQUIRE(expected.width == actual.width);
            REQUIRE(expected.height == actual.height);
            render::Image diff = actual;
            int off = 0;
            float worst = 0;
            for (int y = 0; y < actual.height; ++y)
                for (int x = 0; x < actual.width; ++x) {
                    const float* a = actual.pixel(x, y);
                    const float* b = expected.pixel(x, y);
                    float* d = diff.pixel(x, y);
                    float m = 0;
                    for (int k = 0; k < 3; ++k) {
                        d[k] = std::min(1.0f, 8.0f * std::fabs(a[k] - b[k]));
                        m = std::max(m, std::fabs(a[k] - b[k]));
                    }
                    worst = std::max(worst, m);
                    off += m > 2.5f / 255.0f;
                }
            fs::path diff_png = temp_dir() / (in.stem().string() + ".diff.png");
            if (off > 0) render::write_png(diff_png.string(), diff, &err);
            INFO(off << " pixels differ by more than 2/255 (worst " << worst * 255 << "/255); difference image: " << diff_png.string());
            CHECK(off <= actual.width * actual.height / 200);
        }
    }
}
