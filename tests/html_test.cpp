// `--target html`: the page embeds the webgl2 shader and the parameter description as HTML-safe JSON;
// its script, run by tests/js/page_harness.js in node against a minimal DOM and a recording WebGL2 stub,
// builds one slider per parameter component, sends every uniform at its default, and sends a moved
// slider's value on the next frame. A hostile title stays text.
#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "TestUtil.h"
#include "scene/Page.h"

using namespace iqc::test;

namespace {

size_t occurrences(const std::string& text, const std::string& needle) {
    size_t n = 0;
    for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
    return n;
}

nlohmann::json run_harness(const std::filesystem::path& page) {
    auto out = temp_dir() / (page.filename().string() + ".harness.json");
    std::string cmd = "node " + std::string(IQC_SOURCE_DIR) + "/tests/js/page_harness.js " + page.string() + " > " +
                      out.string() + " 2>&1";
    int rc = std::system(cmd.c_str());
    std::string text = read_text(out);
    INFO("node (installed by scripts/install-deps.sh) said: " << text);
    REQUIRE(rc == 0);
    return nlohmann::json::parse(text);
}

}  // namespace

TEST_CASE("JSON for an HTML script element escapes what could end the element", "[html]") {
    CHECK(iqc::json_string_for_html("a\"b\\c\n</script>&\x01") ==
          "\"a\\\"b\\\\c\\n\\u003c/script\\u003e\\u0026\\u0001\"");
    CHECK(iqc::json_string_for_html("x\xE2\x80\xA8y") == "\"x\\u2028y\"");
    CHECK(iqc::json_string_for_html("‖p‖ ∈ ℝ³") == "\"‖p‖ ∈ ℝ³\"");
    CHECK(iqc::json_for_html("{\"t\": \"<b>&</b>\"}") == "{\"t\": \"\\u003cb\\u003e\\u0026\\u003c/b\\u003e\"}");
}

TEST_CASE("every example becomes a working page: sliders, uniforms, a moved slider", "[html]") {
    for (const char* name : {"two_tori.md", "box_frames.md", "full_phong.md", "simple_phong.md", "gallery.iq",
                             "lights_and_effects.iq", "christmas_tree.iq", "menger.iq", "glass_and_mirror.iq"}) {
        INFO(name);
        auto in = std::filesystem::path(IQC_SOURCE_DIR) / "examples" / name;
        auto page = temp_dir() / (std::string(name) + ".html");
        auto meta_path = temp_dir() / (std::string(name) + ".json");
        RunResult r = run_iqc(in.string() + " --target html -o " + page.string() + " --meta " + meta_path.string());
        INFO(r.err);
        REQUIRE(r.exit_code == 0);
        std::string html = read_text(page);
        CHECK_THAT(html, Catch::StartsWith("<!DOCTYPE html>"));
        CHECK_THAT(html, !Catch::Contains("http://") && !Catch::Contains("https://"));  // offline: nothing fetched
        // Deterministic.
        CHECK(run_iqc(in.string() + " --target html").out == html);
        auto meta = nlohmann::json::parse(read_text(meta_path));
        size_t components = 0;
        for (const auto& p : meta["parameters"])
            if (p.contains("uniform") && p["uniform"].is_string()) components += p["default"].size();
        auto h = run_harness(page);
        CHECK(h["error"].is_null());
        CHECK(h["title"] == meta["title"]);
        // A slider per component, except colours: a picker each (three components), lights' with an intensity.
        CHECK(h["sliders"].get<size_t>() + 3 * h["colours"].get<size_t>() == components);
        size_t lights = 0;
        for (const auto& p : meta["parameters"])
            if (p["role"] == "light" && p["name"] == "color") ++lights;
        CHECK(h["colours"].get<size_t>() >= lights);
        CHECK(h["fragment_shader_chars"].get<size_t>() > 1000);
        // The first frame sends every parameter at its default.
        std::map<std::string, std::vector<double>> first;
        for (const auto& c : h["first"]) first[c[0].get<std::string>()] = c[1].get<std::vector<double>>();
        for (const auto& p : meta["parameters"]) {
            if (!p.contains("uniform") || !p["uniform"].is_string()) continue;
            std::string u = p["uniform"];
            REQUIRE(first.count(u));
            auto want = p["default"].get<std::vector<double>>();
            REQUIRE(first[u].size() == want.size());
            for (size_t i = 0; i < want.size(); ++i) CHECK(first[u][i] == Approx(want[i]).margin(1e-6));
        }
        // And the scene's camera (the shader takes it as uniforms on every target but Shadertoy).
        REQUIRE(meta.contains("camera"));
        for (const auto& [u, v] : meta["camera"]["defaults"].items()) {
            INFO(u);
            REQUIRE(first.count(u));
            std::vector<double> want = v.is_array() ? v.get<std::vector<double>>() : std::vector<double>{v.get<double>()};
            REQUIRE(first[u].size() == want.size());
            for (size_t i = 0; i < want.size(); ++i) CHECK(first[u][i] == Approx(want[i]).margin(1e-6));
        }
        if (components > 0) {
            std::string u = h["moved"]["uniform"];
            size_t k = h["moved"]["component"];
            bool sent = false;
            for (const auto& c : h["last"])
                if (c[0] == u) {
                    sent = true;
                    CHECK(c[1][k].get<double>() == Approx(h["moved"]["max"].get<double>()));
                }
            CHECK(sent);
        }
    }
}

TEST_CASE("a colour picker gives the shader linear light where the output is sRGB", "[html]") {
    // Mid grey (#808080) picked in the page: 128/255 as it is for a document's linear output, decoded from
    // sRGB (0.2158) for a scene's sRGB output.
    auto picked = [](const std::string& name, const std::string& text) {
        auto in = write_temp(name, text);
        auto page = temp_dir() / (name + ".html");
        RunResult r = run_iqc(in.string() + " --target html -o " + page.string());
        REQUIRE(r.exit_code == 0);
        auto h = run_harness(page);
        INFO(h.dump());
        REQUIRE(h["picked"].is_object());
        std::string key = h["picked"]["key"];
        for (const auto& c : h["picked"]["frame"])
            if (c[0] == key) return c[1].get<std::vector<double>>();
        FAIL("the picked colour's uniform was not sent");
        return std::vector<double>{};
    };
    const std::string scene = "[[shapes]]\ntype = \"sphere\"\nmaterial = \"phong\"\n";
    std::vector<double> srgb = picked("picker_srgb.iq", scene);
    std::vector<double> linear = picked("picker_linear.iq", scene + "[render]\noutput = \"linear\"\n");
    REQUIRE(srgb.size() == 3);
    REQUIRE(linear.size() == 3);
    for (int i = 0; i < 3; ++i) {
        CHECK(srgb[size_t(i)] == Approx(0.2158).margin(1e-3));
        CHECK(linear[size_t(i)] == Approx(128.0 / 255).margin(1e-3));
    }
}

TEST_CASE("a hostile title is shown as text, never run", "[html]") {
    const std::string hostile = "</script><script>alert(1)</script>";
    auto in = write_temp("hostile.iq", "title = \"" + hostile +
                                           "\"\n[modules]\nball = \"\"\"\nshape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\n"
                                           "r ∈ [0,3] default = 1: </script><b>radius\n\"\"\"\n[[shapes]]\ntype = \"ball\"\n");
    auto page = temp_dir() / "hostile.html";
    RunResult r = run_iqc(in.string() + " --target html -o " + page.string());
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    std::string html = read_text(page);
    CHECK(occurrences(html, "</script>") == 3);  // the page's own three script elements, nothing from the scene
    CHECK_THAT(html, !Catch::Contains("<script>alert"));
    CHECK_THAT(html, !Catch::Contains("<b>radius"));
    auto h = run_harness(page);
    CHECK(h["title"] == hostile);
    CHECK(h["heading"] == hostile);
    bool label = false;
    for (const auto& l : h["labels"]) label = label || l.get<std::string>().find("</script><b>radius") != std::string::npos;
    CHECK(label);
}
