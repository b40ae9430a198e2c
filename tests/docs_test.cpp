// The documentation's links and pictures resolve (issue 15, "docs that are tested"): every Markdown link or
// image in README.md and docs/*.md that points into the repository names a file that exists, relative to the
// page. Code blocks and inline code are not links. (docs/accuracy.md pointed its plots and CSVs at docs/
// instead of docs/accuracy/.)
#include <catch2/catch.hpp>

#include <filesystem>
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

}  // namespace

TEST_CASE("every link and image in README.md and docs/ that points into the repository resolves", "[docs]") {
    fs::path root(IQC_SOURCE_DIR);
    std::vector<fs::path> pages = {root / "README.md"};
    for (auto& e : fs::directory_iterator(root / "docs"))
        if (e.path().extension() == ".md") pages.push_back(e.path());
    std::sort(pages.begin(), pages.end());
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
