// The documentation's links and pictures resolve (issue 15, "docs that are tested"): every Markdown link or
// image in README.md and docs/*.md that points into the repository names a file that exists, relative to the
// page. Code blocks and inline code are not links. (docs/accuracy.md pointed its plots and CSVs at docs/
// instead of docs/accuracy/.)
#include <catch2/catch.hpp>

#include <filesystem>
#include <fmt/format.h>
#include <fstream>
#include <regex>

#include "TestUtil.h"

using namespace iqc;
namespace fs = std::filesystem;

namespace {

// The page's text without fenced code blocks (``` or ````) and inline code spans.
std::string prose(const std::string& text) {
    std::string out;
    bool fenced = false;
    size_t pos = 0;
    while (pos < text.size()) {
        size_t eol = text.find('\n', pos);
        if (eol == std::string::npos) eol = text.size();
        std::string line = text.substr(pos, eol - pos);
        size_t h = line.find_first_not_of(' ');
        if (h != std::string::npos && line.compare(h, 3, "```") == 0) fenced = !fenced;
        else if (!fenced) out += std::regex_replace(line, std::regex("`[^`]*`"), "") + "\n";
        pos = eol + 1;
    }
    return out;
}

// README.md and docs/*.md, in order.
std::vector<fs::path> doc_pages() {
    fs::path root(IQC_SOURCE_DIR);
    std::vector<fs::path> pages = {root / "README.md"};
    for (auto& e : fs::directory_iterator(root / "docs"))
        if (e.path().extension() == ".md") pages.push_back(e.path());
    std::sort(pages.begin(), pages.end());
    return pages;
}

}  // namespace

TEST_CASE("every link and image in README.md and docs/ that points into the repository resolves", "[docs]") {
    const std::vector<fs::path> pages = doc_pages();
    const std::regex link(R"(\]\(([^)\s]+)\))");
    int checked = 0;
    for (const auto& page : pages) {
        std::string text = prose(test::read_text(page));
        for (std::sregex_iterator it(text.begin(), text.end(), link), end; it != end; ++it) {
            std::string target = (*it)[1];
            if (target.rfind("http://", 0) == 0 || target.rfind("https://", 0) == 0 || target.rfind("mailto:", 0) == 0 || target[0] == '#')
                continue;
            std::string path = target.substr(0, target.find('#'));
            INFO(page.filename().string() << " links to " << target);
            CHECK(fs::exists(page.parent_path() / path));
            ++checked;
        }
    }
    CHECK(checked > 50);
}

TEST_CASE("every TOML scene in README.md and docs/ compiles as written", "[docs]") {
    // docs/scene.md's schema example named a `phong` parameter `D` that does not exist (issue 15). A scene's
    // `include` files are stood in for by a small shape module of the same name.
    const std::vector<fs::path> pages = doc_pages();
    int compiled = 0;
    for (const auto& page : pages) {
        std::string text = test::read_text(page);
        for (size_t at = text.find("```toml\n"); at != std::string::npos; at = text.find("```toml\n", at + 1)) {
            size_t begin = at + 8, end = text.find("\n```", begin);
            REQUIRE(end != std::string::npos);
            std::string scene = text.substr(begin, end - begin + 1);
            std::string name = fmt::format("{}_{}.iq", page.stem().string(), compiled);
            fs::path path = test::write_temp(name, scene);
            const std::regex include(R"re("([A-Za-z0-9_]+)\.iql")re");
            size_t inc = scene.find("include");
            if (inc != std::string::npos)
                for (std::sregex_iterator it(scene.begin() + long(inc), scene.begin() + long(scene.find('\n', inc)), include), e; it != e; ++it)
                    std::ofstream(path.parent_path() / ((*it)[1].str() + ".iql")) << "shape\nD = ‖p‖ - 1\nwhere\np ∈ ℝ³\n";
            test::Compiled c = test::compile_path(path);
            INFO(page.filename().string() << " block at byte " << at << "\n" << c.diagnostics << c.result.internal);
            CHECK(c.result.exit_code == 0);
            ++compiled;
        }
    }
    CHECK(compiled >= 2);
}

TEST_CASE("every module snippet in README.md and docs/ compiles as written", "[docs]") {
    // A ```iheartla block is a whole module: compiled alone (a shape at the origin; a material on a sphere).
    int compiled = 0;
    for (const auto& page : doc_pages()) {
        std::string text = test::read_text(page);
        for (size_t at = text.find("```iheartla\n"); at != std::string::npos; at = text.find("```iheartla\n", at + 1)) {
            size_t begin = at + 12, end = text.find("\n```", begin);
            REQUIRE(end != std::string::npos);
            std::string module = text.substr(begin, end - begin + 1);
            std::string stem = fmt::format("{}_module_{}", page.stem().string(), compiled);
            fs::path path = test::write_temp(stem + ".iql", module);
            if (module.rfind("material", 0) == 0)  // a material is shown on a sphere, as the stdlib reference does
                path = test::write_temp(stem + ".iq", "include = [\"" + stem + ".iql\"]\n[[shapes]]\ntype = \"sphere\"\n"
                                                      "material = \"" + stem + "\"\n");
            test::Compiled c = test::compile_path(path);
            INFO(page.filename().string() << " block at byte " << at << "\n" << c.diagnostics << c.result.internal);
            CHECK(c.result.exit_code == 0);
            ++compiled;
        }
    }
    CHECK(compiled >= 2);
}

TEST_CASE("every shell block marked tested in README.md and docs/ runs as written", "[docs]") {
    // A ```sh block right after a `<!-- tested` comment is run by bash -e in a fresh folder holding examples/
    // (a link to the repository's), with the built iqc first on PATH: docs/engines.md's commands for each target
    // and the validators of other projects that check their output.
    const std::vector<fs::path> pages = doc_pages();
    std::string iqc_dir = fs::path(IQC_BINARY).parent_path().string();
    int ran = 0;
    for (const auto& page : pages) {
        std::string text = test::read_text(page);
        const std::string mark = "<!-- tested";
        for (size_t at = text.find(mark); at != std::string::npos; at = text.find(mark, at + 1)) {
            size_t open = text.find("```sh\n", at);
            REQUIRE(open != std::string::npos);
            REQUIRE(text.find("\n\n", at) > open - 1);  // the block follows the mark directly
            size_t begin = open + 6, end = text.find("\n```", begin);
            REQUIRE(end != std::string::npos);
            std::string script = text.substr(begin, end - begin + 1);
            fs::path dir = test::temp_dir() / fmt::format("docs_sh_{}_{}", page.stem().string(), ran);
            fs::remove_all(dir);
            fs::create_directories(dir);
            fs::create_directory_symlink(fs::path(IQC_SOURCE_DIR) / "examples", dir / "examples");
            fs::path file = test::write_temp(fmt::format("docs_sh_{}_{}.sh", page.stem().string(), ran), script);
            std::string cmd = fmt::format("cd '{}' && PATH='{}':\"$PATH\" bash -e '{}' > out.txt 2>&1", dir.string(), iqc_dir, file.string());
            int rc = std::system(cmd.c_str());
            INFO(page.filename().string() << " block at byte " << open << ":\n" << script << "\n" << test::read_text(dir / "out.txt"));
            CHECK(rc == 0);
            ++ran;
        }
    }
    CHECK(ran >= 3);
}
