#include "scene/Scene.h"

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fmt/format.h>
#include <limits>
#include <toml++/toml.h>
#include <unordered_map>

#include "scene/Modules.h"
#include "sema/Check.h"
#include "source/Limits.h"

namespace iqc {

namespace fs = std::filesystem;

namespace {

// Byte offsets of toml++'s positions (1-based lines and columns, columns in code points) in a file's text
// that starts at `base`: a line's code points are indexed once, at its first use, so locating every
// node of a scene costs time linear in its size (rescanning from `base` per node was quadratic).
class TomlPositions {
public:
    TomlPositions(const SourceManager& sm, FileId file, uint32_t base)
        : sm_(sm), file_(file), first_line_(sm.line_col(file, base).line), base_(base) {}

    uint32_t offset(uint32_t line, uint32_t col) {
        std::string_view text = sm_.text(file_);
        uint32_t l = first_line_ + line - 1;
        std::string_view lt = sm_.line_text(file_, l);
        if (lt.data() == nullptr) return uint32_t(text.size());
        uint32_t start = line == 1 ? base_ : uint32_t(lt.data() - text.data());
        auto it = lines_.find(l);
        if (it == lines_.end()) {
            std::vector<uint32_t> cps;  // byte offset of each code point of the line, and of its end
            size_t end = size_t(lt.data() - text.data()) + lt.size();
            for (size_t i = start; i < end;) {
                cps.push_back(uint32_t(i));
                utf8::decode(text, i);
            }
            cps.push_back(uint32_t(end));
            it = lines_.emplace(l, std::move(cps)).first;
        }
        const auto& cps = it->second;
        return col == 0 ? cps.front() : cps[std::min<size_t>(col - 1, cps.size() - 1)];
    }

private:
    const SourceManager& sm_;
    FileId file_;
    uint32_t first_line_, base_;
    std::unordered_map<uint32_t, std::vector<uint32_t>> lines_;
};

// Where TOML text first nests deeper than limits::kMaxTomlDepth, counting the parts of a dotted key
// (`a.b.c`) and the open arrays and inline tables around it; npos when it never does. toml++ recurses
// that deep while it builds and frees the tables, so a 100,000-part key would overflow the stack. The
// count is a slight over-estimate (a table header's bracket, a float's point), never an under-estimate.
size_t toml_too_deep(std::string_view t) {
    int open = 0, parts = 0;
    auto skip_string = [&](size_t i) {  // i at the opening quote; returns the index of the closing one
        char q = t[i];
        bool multi = t.substr(i, 3) == std::string(3, q);
        size_t j = i + (multi ? 3 : 1);
        for (; j < t.size(); ++j) {
            if (q == '"' && t[j] == '\\') { ++j; continue; }
            if (!multi && (t[j] == q || t[j] == '\n')) return j;
            if (multi && t.substr(j, 3) == std::string(3, q)) return j + 2;
        }
        return t.size();
    };
    for (size_t i = 0; i < t.size(); ++i) {
        char c = t[i];
        if (c == '#') {
            while (i < t.size() && t[i] != '\n') ++i;
            parts = 0;
        } else if (c == '"' || c == '\'') {
            i = skip_string(i);
        } else if (c == '[' || c == '{') {
            ++open;
            parts = 0;
        } else if (c == ']' || c == '}') {
            open = std::max(0, open - 1);
            parts = 0;
        } else if (c == '.') {
            ++parts;
        } else if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '+' || c == ' ' || c == '\t')) {
            parts = 0;
        }
        if (open + parts > limits::kMaxTomlDepth) return i;
    }
    return std::string_view::npos;
}

constexpr size_t kMaxLights = 256;
// The error for a module name that could not be a file's (ModuleLibrary::is_file_name): `type` names a scene's
// modules, an included file and a .iql file alike.
std::string bad_module_name(const std::string& raw) {
    size_t cut = std::min<size_t>(raw.size(), 60);
    while (cut < raw.size() && cut > 0 && (static_cast<unsigned char>(raw[cut]) & 0xC0) == 0x80) --cut;  // a whole UTF-8 character
    std::string name = escape_controls(std::string_view(raw).substr(0, cut));  // the message stays one line
    if (cut < raw.size()) name += "…";
    return fmt::format("'{}' cannot name a module: a name is not empty, does not start with '.', holds no '/', '\\' or "
                       "control characters, and has at most 200 bytes (it names a .iql file too)",
                       name);
}

const std::vector<std::string> kTopKeys = {"title", "include", "modules", "camera", "render", "effects", "lights", "shapes", "blends"};
const std::vector<std::string> kShapeKeys = {"name", "type", "material", "transform", "shape_params", "material_params", "bound",
                                             "glow", "glow_radius"};
const std::vector<std::string> kCameraKeys = {"position", "target", "fov", "orbit"};
const std::vector<std::string> kRenderKeys = {"march", "max_steps", "max_dist", "hit", "hit_mode", "normals",
                                              "background", "relaxation", "step", "debug", "output",
                                              "tonemap", "exposure", "vignette", "contrast"};
const std::vector<std::string> kEffectKeys = {"shadows", "shadow_softness", "ao", "fog", "fog_color", "fog_mode", "reflections",
                                              "refraction", "antialias"};
const std::vector<std::string> kLightKeys = {"name", "type", "position", "direction", "color"};

class SceneReader {
public:
    SceneReader(SourceManager& sm, Diagnostics& d, SceneDesc& s, FileId file, uint32_t base)
        : sm_(sm), d_(d), s_(s), file_(file), base_(base), positions_(sm, file, base) {}

    void read(std::string_view toml_text);
    // The parts of a scene, each from its top-level key (errors are located diagnostics).
    void read_includes(const toml::table& root);
    void read_modules(const toml::table& root);
    void read_camera(const toml::table& root);
    void read_render(const toml::table& root);
    void read_effects(const toml::table& root);
    void read_lights(const toml::table& root);
    void read_blends(const toml::table& root);
    void read_shapes(const toml::table& root);
    std::optional<InstanceDesc> read_shape(const toml::node& item);

private:
    SourceManager& sm_;
    Diagnostics& d_;
    SceneDesc& s_;
    FileId file_;
    uint32_t base_;  // offset of the TOML text in the file (a document's scene block)
    TomlPositions positions_;

    Span span_of(const toml::source_region& r) {
        uint32_t b = positions_.offset(r.begin.line ? r.begin.line : 1, r.begin.column ? r.begin.column : 1);
        uint32_t e = r.end.line ? positions_.offset(r.end.line, r.end.column) : b + 1;
        if (e <= b) e = b + 1;
        // Keep the span on one line for the caret.
        std::string_view t = sm_.text(file_);
        for (uint32_t k = b; k < e && k < t.size(); ++k)
            if (t[k] == '\n') { e = k; break; }
        if (e <= b) e = b + 1;
        return {file_, b, e};
    }
    Span span_of(const toml::node& n) { return span_of(n.source()); }

    static const char* type_name(const toml::node& n) {
        if (n.is_string()) return "a string";
        if (n.is_integer()) return "an integer";
        if (n.is_floating_point()) return "a number";
        if (n.is_boolean()) return "a boolean";
        if (n.is_array()) return "an array";
        if (n.is_table()) return "a table";
        return "a date or time";
    }
    void wrong_type(const toml::node& n, const std::string& key, const char* want) {
        d_.error(span_of(n), fmt::format("'{}' must be {}, not {}", key, want, type_name(n)));
    }
    void check_keys(const toml::table& t, const std::vector<std::string>& allowed, const std::string& where) {
        for (auto&& [k, v] : t) {
            std::string key(k.str());
            if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
            auto& e = d_.error(span_of(k.source()), fmt::format("unknown field '{}'{}", key, where));
            if (auto s = did_you_mean(key, allowed)) Diagnostics::note(e, span_of(k.source()), fmt::format("did you mean '{}'?", *s));
        }
    }
    // A string that must be one of `choices`; returns its index.
    std::optional<size_t> get_choice(const toml::node& n, const std::string& key, const std::vector<std::string>& choices) {
        auto v = get_string(n, key);
        if (!v) return std::nullopt;
        for (size_t i = 0; i < choices.size(); ++i)
            if (*v == choices[i]) return i;
        std::string list;
        for (size_t i = 0; i < choices.size(); ++i) list += (i ? ", " : "") + choices[i];
        auto& e = d_.error(span_of(n), fmt::format("unknown {} '{}': choose one of {}", key, *v, list));
        if (auto s = did_you_mean(*v, choices)) Diagnostics::note(e, span_of(n), fmt::format("did you mean '{}'?", *s));
        return std::nullopt;
    }
    std::optional<bool> get_bool(const toml::node& n, const std::string& key) {
        if (n.is_boolean()) return *n.value<bool>();
        wrong_type(n, key, "true or false");
        return std::nullopt;
    }
    std::optional<int> get_int(const toml::node& n, const std::string& key, int lo, int hi) {
        if (!n.is_integer() || *n.value<int64_t>() < lo || *n.value<int64_t>() > hi) {
            if (!n.is_integer()) wrong_type(n, key, "a whole number");
            else d_.error(span_of(n), fmt::format("'{}' must be from {} to {}", key, lo, hi));
            return std::nullopt;
        }
        return int(*n.value<int64_t>());
    }

    std::optional<std::string> get_string(const toml::node& n, const std::string& key) {
        if (auto v = n.value<std::string>(); v && n.is_string()) return *v;
        wrong_type(n, key, "a string");
        return std::nullopt;
    }
    std::optional<double> get_number(const toml::node& n, const std::string& key) {
        if (n.is_number()) return in_float_range(n, key);
        wrong_type(n, key, "a number");
        return std::nullopt;
    }
    // A number's value when it is finite and within 32-bit floats' range (what shaders compute in; TOML
    // also allows inf and nan), else a located error.
    std::optional<double> in_float_range(const toml::node& n, const std::string& key) {
        // toml++ gives no double for an integer beyond 2^53 (it would round): such an integer is read as the
        // nearest double, as a literal would be (it was silently 0).
        double v = n.is_integer() ? double(*n.value<int64_t>()) : n.value<double>().value_or(std::nan(""));
        // Within range where it rounds to a finite float (3.4028235e38, FLT_MAX as printed, rounds down to it).
        if (!limits::fits_float(v)) {
            d_.error(span_of(n), fmt::format("'{}' must be a finite number within the range of 32-bit floats (about ±3.4e38), "
                                             "not {}", key, v));
            return std::nullopt;
        }
        // Below the smallest normal float a shader has 0 (or a denormal a GPU may flush): the rule of a literal
        // in a module, and of the same number written as a string ("1e-50").
        if (limits::below_normal_float(v)) {
            d_.error(span_of(n), fmt::format("'{}' is {}, below the smallest normal 32-bit float (about 1.2e-38), which shaders "
                                             "compute in: it would be 0 there", key, v));
            return std::nullopt;
        }
        return v;
    }
    std::optional<std::vector<double>> get_numbers(const toml::node& n, const std::string& key) {
        if (n.is_number()) {
            auto v = in_float_range(n, key);
            if (!v) return std::nullopt;
            return std::vector<double>{*v};
        }
        if (!n.is_array()) {
            wrong_type(n, key, "a number or an array of numbers");
            return std::nullopt;
        }
        std::vector<double> out;
        for (auto& x : *n.as_array()) {
            if (!x.is_number()) {
                wrong_type(x, key, "a number");
                return std::nullopt;
            }
            auto v = in_float_range(x, key);
            if (!v) return std::nullopt;
            out.push_back(*v);
        }
        return out;
    }
    bool get_vec3(const toml::node& n, const std::string& key, std::array<double, 3>& out) {
        auto v = get_numbers(n, key);
        if (!v) return false;
        if (v->size() != 3) {
            d_.error(span_of(n), fmt::format("'{}' must have 3 components, not {}", key, v->size()));
            return false;
        }
        out = {(*v)[0], (*v)[1], (*v)[2]};
        return true;
    }

    // The text of a TOML string value as module source: its bytes in the file when verbatim, else an
    // embedded copy located at the string.
    ModuleSource string_source(const toml::node& n, const std::string& value, const std::string& name, const char* origin) {
        ModuleSource ms;
        ms.name = name;
        ms.origin = origin;
        Span s = span_of(n);
        ms.where = s;
        std::string_view t = sm_.text(file_);
        uint32_t off = s.begin;
        uint32_t content = off;
        bool basic = false, multiline = false;
        if (t.substr(off, 3) == "\"\"\"" || t.substr(off, 3) == "'''") {
            basic = t[off] == '"';
            multiline = true;
            content = off + 3;
            if (t.substr(content, 1) == "\n") content += 1;
            else if (t.substr(content, 2) == "\r\n") content += 2;
        } else if (t.substr(off, 1) == "\"" || t.substr(off, 1) == "'") {
            basic = t[off] == '"';
            content = off + 1;
        }
        if (t.substr(content, value.size()) == value) {
            ms.file = file_;
            ms.ranges = {{content, uint32_t(content + value.size())}};
        } else {
            std::vector<uint32_t> map;
            if (basic) map = escapes_map(t, content, multiline, value);
            ms.file = map.empty() ? sm_.add_embedded(sm_.name(file_), value, file_, content)
                                  : sm_.add_embedded(sm_.name(file_), value, file_, std::move(map));
            ms.ranges = {{0, uint32_t(value.size())}};
        }
        return ms;
    }

    // For a TOML basic string whose text starts at `content` of the file `t`: the file offset of each byte of its
    // value (and of its end), reading its escapes (\n, \", \\, \uXXXX, \UXXXXXXXX, a line-ending backslash of a
    // multi-line string); empty where the value does not follow from the text (then the string's start is used,
    // and diagnostics count lines within the value). A new user's trial: a module written "shape\nD = …\n" was
    // reported at lines the file does not have.
    static std::vector<uint32_t> escapes_map(std::string_view t, uint32_t content, bool multiline, const std::string& value) {
        std::vector<uint32_t> map;
        map.reserve(value.size() + 1);
        size_t r = content, v = 0;
        auto hex = [&](size_t at, int n, uint32_t& cp) {
            cp = 0;
            for (int k = 0; k < n; ++k) {
                if (at + size_t(k) >= t.size() || !std::isxdigit(static_cast<unsigned char>(t[at + size_t(k)]))) return false;
                char c = t[at + size_t(k)];
                cp = cp * 16 + uint32_t(std::isdigit(static_cast<unsigned char>(c)) ? c - '0' : (std::tolower(c) - 'a' + 10));
            }
            return true;
        };
        while (v < value.size()) {
            if (r >= t.size()) return {};
            char c = t[r];
            if (c == '\\') {
                if (r + 1 >= t.size()) return {};
                char e = t[r + 1];
                size_t raw = 2, bytes = 1;
                if (e == 'u' || e == 'U') {
                    int n = e == 'u' ? 4 : 8;
                    uint32_t cp;
                    if (!hex(r + 2, n, cp)) return {};
                    raw = 2 + size_t(n);
                    bytes = cp < 0x80 ? 1 : cp < 0x800 ? 2 : cp < 0x10000 ? 3 : 4;
                } else if (multiline && (e == ' ' || e == '\t' || e == '\n' || e == '\r')) {
                    // a line-ending backslash: it and the whitespace and newlines after it are no part of the value
                    size_t k = r + 1;
                    while (k < t.size() && (t[k] == ' ' || t[k] == '\t' || t[k] == '\n' || t[k] == '\r')) ++k;
                    r = k;
                    continue;
                } else if (std::string_view("btnfr\"\\e").find(e) == std::string_view::npos) {
                    return {};
                }
                if (v + bytes > value.size()) return {};
                for (size_t k = 0; k < bytes; ++k) map.push_back(uint32_t(r));
                v += bytes;
                r += raw;
            } else if (c == '\r' && r + 1 < t.size() && t[r + 1] == '\n' && value[v] == '\n') {
                map.push_back(uint32_t(r));
                ++v;
                r += 2;
            } else {
                if (value[v] != c) return {};
                map.push_back(uint32_t(r));
                ++v;
                ++r;
            }
        }
        map.push_back(uint32_t(r));
        return map;
    }

    void read_params(const toml::node& n, const std::string& key, std::vector<ParamOverride>& out) {
        if (!n.is_table()) {
            wrong_type(n, key, "a table such as { r = 1.5 }");
            return;
        }
        for (auto&& [k, v] : *n.as_table()) {
            std::string name(k.str());
            ParamOverride ov{name, {}, span_of(k.source())};
            if (auto* s = v.as_string()) {  // a constant expression, evaluated as any value is
                SourceManager scratch;
                Diagnostics quiet(scratch);
                auto value = ModuleLibrary::evaluate_constant(name, s->get(), scratch, quiet);
                if (!value) {
                    std::string why = quiet.all().empty() ? "" : ": " + quiet.all().front().message;
                    d_.error(span_of(v), fmt::format("'{}' must be a number, an array, or a constant expression such as "
                                                     "\"√2\"; this string is not one{}", name, why));
                    continue;
                }
                ov.value = value->v;
                if (value->type.is_matrix()) ov.rows = value->type.rows, ov.cols = value->type.cols;
                out.push_back(std::move(ov));
                continue;
            }
            if (auto* rows = v.as_array(); rows && !rows->empty() && (*rows)[0].is_array()) {  // a matrix, row by row
                bool ok = true;
                for (auto& row : *rows) {
                    auto nums = row.is_array() ? get_numbers(row, name) : std::nullopt;
                    if (!row.is_array()) wrong_type(row, name, "a row: an array of numbers");
                    if (!nums) { ok = false; break; }
                    if (ov.rows > 0 && int(nums->size()) != ov.cols) {
                        d_.error(span_of(row), fmt::format("the rows of '{}' must have one length: this one has {}, the first {}",
                                                           name, nums->size(), ov.cols));
                        ok = false;
                        break;
                    }
                    ov.cols = int(nums->size());
                    ++ov.rows;
                    ov.value.insert(ov.value.end(), nums->begin(), nums->end());
                }
                if (ok) out.push_back(std::move(ov));
                continue;
            }
            auto nums = get_numbers(v, name);
            if (!nums) continue;
            ov.value = *nums;
            out.push_back(std::move(ov));
        }
    }
};

void SceneReader::read(std::string_view text) {
    if (size_t at = toml_too_deep(text); at != std::string_view::npos) {
        d_.error({file_, uint32_t(base_ + at), uint32_t(base_ + at + 1)},
                 fmt::format("the TOML nests deeper than {} levels here (the parts of a dotted key plus the arrays "
                             "and tables around it)", limits::kMaxTomlDepth));
        return;
    }
    toml::table root;
    try {
        root = toml::parse(text, sm_.name(file_));
    } catch (const toml::parse_error& e) {
        Span s = span_of(e.source());
        auto& err = d_.error(s, fmt::format("invalid TOML: {}", e.description()));
        // An unquoted key with a letter such as θ: TOML's bare keys are ASCII.
        std::string_view at = sm_.text(s.file).substr(std::min<size_t>(s.begin, sm_.text(s.file).size()));
        if (!at.empty() && static_cast<unsigned char>(at[0]) >= 0x80)
            Diagnostics::note(err, s, "a TOML key with letters such as θ must be quoted (\"θ\" = 1); a Greek letter may also "
                                      "be written with its ASCII name (theta = 1)");
        return;
    }
    check_keys(root, kTopKeys, " in the scene");
    if (auto* n = root.get("title"))
        if (auto v = get_string(*n, "title")) {
            // Written into every output's comments (and an HTML page twice): a 3 MB title made a 6 MB page.
            if (v->size() > 1000) d_.error(span_of(*n), fmt::format("the title has {} bytes: at most 1000", v->size()));
            else s_.title = *v;
        }
    read_includes(root);
    read_modules(root);
    read_camera(root);
    read_render(root);
    read_effects(root);
    read_lights(root);
    read_shapes(root);
    read_blends(root);
}

// [[blends]]: shapes = ["a", "b", ...] (instance names, resolved when instances are planned), radius = k.
void SceneReader::read_blends(const toml::table& root) {
    auto* n = root.get("blends");
    if (!n) return;
    if (!n->is_array_of_tables()) {
        wrong_type(*n, "blends", "an array of tables ([[blends]])");
        return;
    }
    for (auto& item : *n->as_array()) {
        auto& t = *item.as_table();
        check_keys(t, {"shapes", "radius"}, " in [[blends]]");
        BlendDesc b;
        b.span = span_of(item);
        if (auto* x = t.get("radius"))
            if (auto v = get_number(*x, "radius")) {
                if (*v <= 0) d_.error(span_of(*x), "a blend's 'radius' must be positive (how far the smooth union reaches)");
                else b.radius = *v;
            }
        auto* shapes = t.get("shapes");
        if (!shapes || !shapes->is_array()) {
            d_.error(shapes ? span_of(*shapes) : b.span, "a blend needs 'shapes': an array of the names of the instances it joins");
            continue;
        }
        for (auto& e : *shapes->as_array())
            if (auto v = get_string(e, "shapes")) b.shapes.push_back({*v, span_of(e)});
        if (b.shapes.size() < 2) d_.error(span_of(*shapes), "a blend joins at least two instances");
        s_.blends.push_back(std::move(b));
    }
}

void SceneReader::read_includes(const toml::table& root) {
    fs::path dir = fs::path(s_.path).parent_path();
    if (auto* n = root.get("include")) {
        if (!n->is_array()) {
            wrong_type(*n, "include", "an array of file names");
        } else {
            for (auto& item : *n->as_array()) {
                auto rel = get_string(item, "include");
                if (!rel) continue;
                fs::path p = dir / *rel;
                std::string text, err;
                if (!read_source_file(p.string(), sm_.total_bytes(), text, err)) {
                    d_.error(span_of(item), fmt::format("cannot read included file '{}': {}", p.string(), err));
                    continue;
                }
                FileId f = sm_.add_from_disk(p.string(), std::move(text));
                ModuleSource ms;
                ms.name = p.stem().string();
                ms.file = f;
                ms.ranges = {{0, uint32_t(sm_.text(f).size())}};
                ms.where = span_of(item);
                ms.origin = "include";
                s_.modules.push_back(std::move(ms));
            }
        }
    }
}

void SceneReader::read_modules(const toml::table& root) {
    if (auto* n = root.get("modules")) {
        if (!n->is_table()) {
            wrong_type(*n, "modules", "a table of name = \"\"\"source\"\"\"");
        } else {
            for (auto&& [k, v] : *n->as_table()) {
                auto src = get_string(v, std::string(k.str()));
                if (!src) continue;
                if (!ModuleLibrary::is_file_name(std::string(k.str()))) {
                    d_.error(span_of(k.source()), bad_module_name(std::string(k.str())));
                    continue;
                }
                s_.modules.push_back(string_source(v, *src, std::string(k.str()), "scene"));
            }
        }
    }
}

void SceneReader::read_camera(const toml::table& root) {
    if (auto* n = root.get("camera")) {
        if (!n->is_table()) {
            wrong_type(*n, "camera", "a table");
        } else {
            auto& t = *n->as_table();
            check_keys(t, kCameraKeys, " in [camera]");
            if (auto* x = t.get("position")) {
                get_vec3(*x, "position", s_.camera.position);
                s_.camera.position_span = span_of(*x);
            }
            if (auto* x = t.get("target")) get_vec3(*x, "target", s_.camera.target);
            if (auto* x = t.get("fov")) {
                if (auto v = get_number(*x, "fov")) {
                    if (*v <= 0 || *v >= 180) d_.error(span_of(*x), fmt::format("'fov' must be between 0 and 180 degrees, not {}", *v));
                    else s_.camera.fov = *v;
                }
            }
            if (auto* x = t.get("orbit"))
                if (auto v = get_bool(*x, "orbit")) s_.camera.orbit = *v;
            // In the shader's 32-bit floats: the view direction is normalize(target - position), which needs a
            // difference float spacing can resolve, and coordinates where a float still has fractions.
            double scale = 1, gap = 0;
            bool huge = false;
            for (int k = 0; k < 3; ++k) {
                double a = double(float(s_.camera.position[size_t(k)])), b = double(float(s_.camera.target[size_t(k)]));
                scale = std::max({scale, std::fabs(a), std::fabs(b)});
                gap = std::max(gap, std::fabs(b - a));
                huge |= std::fabs(a) > 1e7 || std::fabs(b) > 1e7;
            }
            if (huge)
                d_.error(span_of(*n), "the camera's position and target must be within ±1e7 (beyond, a 32-bit float has "
                                      "no fractions left: the shader's rays would be noise)");
            else if (gap < 1e-5 * scale)
                d_.error(span_of(*n), gap == 0 ? fmt::format("the camera's position and target are the same point in 32-bit floats "
                                                             "(what shaders compute in): they must differ by more than {:.3g}",
                                                             1e-5 * scale)
                                               : fmt::format("the camera's target is too close to its position for coordinates this "
                                                             "large: {:.3g} apart where 32-bit floats (what shaders compute in) are "
                                                             "{:.3g} apart, the view direction is only known to about {:.2g}°; put the "
                                                             "target more than {:.3g} away (1e-5 of the largest coordinate)",
                                                             gap, std::nextafter(float(scale), INFINITY) - float(scale),
                                                             (std::nextafter(float(scale), INFINITY) - float(scale)) / gap * 180 / M_PI,
                                                             1e-5 * scale));
        }
    }
}

void SceneReader::read_render(const toml::table& root) {
    if (auto* n = root.get("render")) {
        if (!n->is_table()) {
            wrong_type(*n, "render", "a table");
        } else {
            auto& t = *n->as_table();
            check_keys(t, kRenderKeys, " in [render]");
            if (auto* x = t.get("max_steps"))
                if (auto v = get_int(*x, "max_steps", 1, kMaxStepsSetting)) {
                    s_.render.max_steps = *v;
                    s_.render.max_steps_span = span_of(*x);
                }
            if (auto* x = t.get("max_dist"))
                if (auto v = get_number(*x, "max_dist")) {
                    if (*v <= 0) d_.error(span_of(*x), "'max_dist' must be positive");
                    else s_.render.max_dist = *v;
                }
            if (auto* x = t.get("hit"))
                if (auto v = get_number(*x, "hit")) {
                    if (*v <= 0) d_.error(span_of(*x), "'hit' must be positive");
                    else s_.render.hit = *v;
                }
            if (auto* x = t.get("background")) {
                if (auto* g = x->as_table()) {
                    // A sky gradient: zenith and horizon (both required), ground (optional).
                    check_keys(*g, {"zenith", "horizon", "ground", "stars"}, " in 'background'");
                    auto* z = g->get("zenith");
                    auto* h = g->get("horizon");
                    if (!z || !h) d_.error(span_of(*x), "a sky-gradient 'background' needs 'zenith' and 'horizon' colours");
                    if (z) get_vec3(*z, "zenith", s_.render.zenith);
                    if (h) get_vec3(*h, "horizon", s_.render.background);
                    if (auto* gr = g->get("ground")) s_.render.has_ground = get_vec3(*gr, "ground", s_.render.ground);
                    if (auto* st = g->get("stars"))
                        if (auto v = get_number(*st, "stars")) {
                            if (*v < 0 || *v > 1) d_.error(span_of(*st), "'stars' (how many stars) must be in [0, 1]");
                            else s_.render.stars = *v;
                        }
                    s_.render.sky_gradient = true;
                } else {
                    get_vec3(*x, "background", s_.render.background);
                }
            }
            if (auto* x = t.get("output"))
                if (auto v = get_choice(*x, "output encoding", {"srgb", "linear"})) s_.render.srgb = *v == 0;
            if (auto* x = t.get("tonemap"))
                if (auto v = get_choice(*x, "tone map", {"none", "reinhard", "aces"})) s_.render.tonemap = RenderDesc::Tonemap(*v);
            if (auto* x = t.get("exposure"))
                if (auto v = get_number(*x, "exposure")) {
                    if (*v <= 0) d_.error(span_of(*x), "'exposure' must be positive");
                    else s_.render.exposure = *v;
                }
            for (auto [key, out] : {std::pair{"vignette", &s_.render.vignette}, std::pair{"contrast", &s_.render.contrast}})
                if (auto* x = t.get(key))
                    if (auto v = get_number(*x, key)) {
                        if (*v < 0 || *v > 1) d_.error(span_of(*x), fmt::format("'{}' must be in [0, 1]", key));
                        else *out = *v;
                    }
            if (auto* x = t.get("march"))
                if (auto v = get_choice(*x, "march method", {"fixed", "sphere", "relaxed", "auto", "segment"})) {
                    s_.render.march = March(*v);
                    s_.render.march_span = span_of(*x);
                }
            if (auto* x = t.get("normals"))
                if (auto v = get_choice(*x, "normals method", {"central", "forward", "tetrahedron", "analytic"}))
                    s_.render.normals = Normals(*v);
            if (auto* x = t.get("hit_mode"))
                if (auto v = get_choice(*x, "hit_mode", {"absolute", "relative"})) s_.render.hit_relative = *v == 1;
            if (auto* x = t.get("relaxation"))
                if (auto v = get_number(*x, "relaxation")) {
                    if (*v < 1 || *v >= 2) d_.error(span_of(*x), "'relaxation' must be in [1, 2)");
                    else s_.render.relaxation = *v;
                }
            if (auto* x = t.get("step"))
                if (auto v = get_number(*x, "step")) {
                    if (*v <= 0) d_.error(span_of(*x), "'step' must be positive");
                    else s_.render.step = *v;
                }
            if (auto* x = t.get("debug"))
                if (auto v = get_choice(*x, "debug view", {"none", "normals", "steps", "depth"})) s_.render.debug = DebugView(*v);
        }
    }
}

void SceneReader::read_effects(const toml::table& root) {
    if (auto* n = root.get("effects")) {
        if (!n->is_table()) {
            wrong_type(*n, "effects", "a table");
        } else {
            auto& t = *n->as_table();
            check_keys(t, kEffectKeys, " in [effects]");
            auto& e = s_.effects;
            if (auto* x = t.get("shadows")) {
                e.shadows_span = span_of(*x);
                // shadows = "soft" (or true for soft, false for none)
                if (x->is_boolean()) e.shadows = *x->value<bool>() ? Shadows::Soft : Shadows::None;
                else if (auto v = get_choice(*x, "shadows", {"none", "hard", "soft"})) e.shadows = Shadows(*v);
            }
            if (auto* x = t.get("shadow_softness"))
                if (auto v = get_number(*x, "shadow_softness")) {
                    if (*v <= 0) d_.error(span_of(*x), "'shadow_softness' must be positive");
                    else e.shadow_softness = *v;
                }
            if (auto* x = t.get("ao"))
                if (auto v = get_bool(*x, "ao")) e.ao = *v;
            if (auto* x = t.get("fog")) {
                if (x->is_boolean()) e.fog = *x->value<bool>() ? 0.02 : 0.0;
                else if (auto v = get_number(*x, "fog")) {
                    if (*v < 0) d_.error(span_of(*x), "'fog' (a density) cannot be negative");
                    else e.fog = *v;
                }
            }
            if (auto* x = t.get("fog_mode"))
                if (auto v = get_choice(*x, "fog mode", {"exp", "exp2"})) e.fog_exp2 = *v == 1;
            if (auto* x = t.get("fog_color")) {
                std::array<double, 3> c;
                if (get_vec3(*x, "fog_color", c)) e.fog_color = c;
            }
            if (auto* x = t.get("reflections")) {
                e.reflections_span = span_of(*x);
                if (x->is_boolean()) e.reflections = *x->value<bool>() ? 1 : 0;
                else if (auto v = get_int(*x, "reflections", 0, 16)) e.reflections = *v;
            }
            if (auto* x = t.get("refraction")) {
                e.refraction_span = span_of(*x);
                if (auto v = get_bool(*x, "refraction")) e.refraction = *v;
            }
            if (auto* x = t.get("antialias")) {
                if (x->is_boolean()) e.antialias = *x->value<bool>() ? 2 : 1;
                else if (auto v = get_int(*x, "antialias", 1, 8)) e.antialias = *v;
            }
        }
    }
}

void SceneReader::read_lights(const toml::table& root) {
    if (auto* n = root.get("lights")) {
        if (!n->is_array_of_tables()) {
            wrong_type(*n, "lights", "an array of tables ([[lights]])");
        } else {
            for (auto& item : *n->as_array()) {
                auto& t = *item.as_table();
                // Every light is a shading pass per pixel: 256 is far past what a shader can afford.
                if (s_.lights.size() >= kMaxLights) {
                    d_.error(span_of(item), fmt::format("a scene has at most {} lights", kMaxLights));
                    break;
                }
                check_keys(t, kLightKeys, " in [[lights]]");
                LightDesc l;
                l.span = span_of(item);
                l.name = fmt::format("light_{}", s_.lights.size() + 1);
                if (auto* x = t.get("name"))
                    if (auto v = get_string(*x, "name")) {
                        if (v->size() > 8192) d_.error(span_of(*x), fmt::format("a light's name has {} bytes: at most 8192", v->size()));
                        else l.name = *v;
                    }
                auto* pos = t.get("position");
                auto* dir = t.get("direction");
                // The kind: `type`, else a sun where only a direction is given, else a point light.
                l.kind = dir && !pos ? LightKind::Sun : LightKind::Point;
                if (auto* x = t.get("type"))
                    if (auto v = get_choice(*x, "light type", {"point", "sun", "sky", "bounce"})) l.kind = LightKind(*v);
                if (pos) get_vec3(*pos, "position", l.position);
                if (dir && get_vec3(*dir, "direction", l.direction)) {
                    double n = std::sqrt(l.direction[0] * l.direction[0] + l.direction[1] * l.direction[1] +
                                         l.direction[2] * l.direction[2]);
                    if (n < 1e-12) d_.error(span_of(*dir), "a light's 'direction' cannot be the zero vector");
                    l.has_direction = true;
                }
                switch (l.kind) {
                    case LightKind::Point:
                        if (!pos) d_.error(l.span, "this [[lights]] entry has no 'position' (a point light; a sun takes a 'direction')");
                        if (dir) d_.error(span_of(*dir), "a point light has no 'direction' (did you mean type = \"sun\"?)");
                        break;
                    case LightKind::Sun:
                        if (!dir) d_.error(l.span, "this sun has no 'direction' (the direction toward the sun, e.g. [0.6, 0.4, -0.5])");
                        [[fallthrough]];
                    case LightKind::Sky:
                    case LightKind::Bounce:
                        if (pos) d_.error(span_of(*pos), fmt::format("a {} light has no 'position'", l.kind == LightKind::Sun ? "sun"
                                                                     : l.kind == LightKind::Sky ? "sky" : "bounce"));
                        if (l.kind == LightKind::Sky && dir)
                            d_.error(span_of(*dir), "a sky light has no 'direction' (it shines from the whole upper hemisphere)");
                        break;
                }
                if (auto* x = t.get("color")) get_vec3(*x, "color", l.color);
                s_.lights.push_back(l);
            }
        }
    }
}

void SceneReader::read_shapes(const toml::table& root) {
    auto* shapes = root.get("shapes");
    if (!shapes) {
        d_.error({file_, base_, base_ + 1}, "the scene has no [[shapes]]: add at least one, e.g. [[shapes]] type = \"sphere\"");
        return;
    }
    if (!shapes->is_array_of_tables()) {
        wrong_type(*shapes, "shapes", "an array of tables ([[shapes]])");
        return;
    }
    for (auto& item : *shapes->as_array()) {
        if (auto inst = read_shape(item)) s_.instances.push_back(std::move(*inst));
    }
}

// One [[shapes]] entry; nothing when it names no shape (reported).
std::optional<InstanceDesc> SceneReader::read_shape(const toml::node& item) {
    auto& t = *item.as_table();
    InstanceDesc inst;
    inst.span = span_of(item);
    check_keys(t, kShapeKeys, " in [[shapes]]");
    if (auto* x = t.get("name"))
        if (auto v = get_string(*x, "name")) {
            inst.name = *v;
            inst.name_span = span_of(*x);
            if (v->empty()) d_.error(inst.name_span, "an instance name cannot be empty");
            // Named in the shader's comments and --meta (a 5 MB name made a 10 MB shader: a new user's trial).
            else if (v->size() > 8192) d_.error(inst.name_span, fmt::format("an instance name has {} bytes: at most 8192", v->size()));
        }
    if (auto* x = t.get("type")) {
        if (auto v = get_string(*x, "type")) {
            inst.type = *v;
            inst.type_span = span_of(*x);
            if (v->empty()) {
                d_.error(inst.type_span, "'type' cannot be empty: name a shape module, e.g. type = \"sphere\"");
                return std::nullopt;
            }
        }
    } else {
        d_.error(inst.span, "this [[shapes]] entry has no 'type' (the shape module to use)");
        return std::nullopt;
    }
    if (auto* x = t.get("material"))
        if (auto v = get_string(*x, "material")) {
            inst.material = *v;
            inst.material_span = span_of(*x);
            if (v->empty())
                d_.error(inst.material_span, "'material' cannot be empty: name a material module, or leave "
                                             "'material' out for the default (the normal as a colour)");
        }
    if (auto* x = t.get("transform"))
        if (auto v = get_string(*x, "transform")) inst.transform = string_source(*x, *v, "transform", "scene");
    if (auto* x = t.get("shape_params")) read_params(*x, "shape_params", inst.shape_params);
    if (auto* x = t.get("material_params")) read_params(*x, "material_params", inst.material_params);
    if (auto* x = t.get("bound"))
        if (auto v = get_number(*x, "bound")) {
            if (!(*v > 0) || !std::isfinite(*v))
                d_.error(span_of(*x), fmt::format("'bound' (a bounding sphere radius) must be positive, not {}", *v));
            else {
                inst.bound = *v;
                inst.bound_span = span_of(*x);
            }
        }
    if (auto* x = t.get("glow")) {
        std::array<double, 3> c{};
        if (get_vec3(*x, "glow", c)) {
            if (c[0] < 0 || c[1] < 0 || c[2] < 0)
                d_.error(span_of(*x), "'glow' is a colour: its components cannot be negative");
            else if (c[0] > 1000 || c[1] > 1000 || c[2] > 1000)
                d_.error(span_of(*x), "'glow' components above 1000 overflow the tone map (at most 1000)");
            else {
                inst.glow = c;
                inst.glow_span = span_of(*x);
            }
        }
    }
    if (auto* x = t.get("glow_radius"))
        if (auto v = get_number(*x, "glow_radius")) {
            if (!(*v > 0) || !std::isfinite(*v))
                d_.error(span_of(*x), fmt::format("'glow_radius' must be positive, not {}", *v));
            else if (*v < 1e-6 || *v > 1e6)
                d_.error(span_of(*x), fmt::format("'glow_radius' must be in [1e-6, 1e6], not {}", *v));
            else if (!t.get("glow"))
                d_.error(span_of(*x), "'glow_radius' without 'glow': give the glow's colour, glow = [r, g, b]");
            else
                inst.glow_radius = *v;
        }
    if (inst.type.empty()) return std::nullopt;
    return inst;
}

bool is_fence(std::string_view line, std::string_view& info) {
    size_t i = 0;
    while (i < line.size() && line[i] == ' ') ++i;
    if (line.substr(i, 3) != "```") return false;
    size_t j = i;
    while (j < line.size() && line[j] == '`') ++j;
    info = line.substr(j);
    while (!info.empty() && (info.back() == ' ' || info.back() == '\r')) info.remove_suffix(1);
    while (!info.empty() && info.front() == ' ') info.remove_prefix(1);
    return true;
}

void read_document(SourceManager& sm, Diagnostics& d, SceneDesc& s) {
    std::string_view t = sm.text(s.file);
    // Split into lines with offsets.
    std::vector<std::pair<uint32_t, uint32_t>> lines;  // begin, end (without newline)
    for (size_t b = 0; b <= t.size();) {
        size_t e = t.find('\n', b);
        if (e == std::string_view::npos) e = t.size();
        lines.push_back({uint32_t(b), uint32_t(e)});
        b = e + 1;
        if (e == t.size()) break;
    }
    std::string pending_name;
    Span pending_span;
    bool have_scene = false;
    std::map<std::string, size_t> by_name;
    for (size_t li = 0; li < lines.size(); ++li) {
        std::string_view line = t.substr(lines[li].first, lines[li].second - lines[li].first);
        std::string_view info;
        for (std::string_view heart : {std::string_view("❤"), std::string_view("♥")}) {
            size_t k = 0;
            while (k < line.size() && line[k] == ' ') ++k;
            if (line.substr(k, heart.size()) == heart) {
                size_t c = k + heart.size();
                if (line.substr(c, 3) == "\xEF\xB8\x8F") c += 3;  // variation selector after ❤
                if (line.substr(c, 1) == ":") {
                    std::string_view name = line.substr(c + 1);
                    while (!name.empty() && (name.front() == ' ')) name.remove_prefix(1);
                    while (!name.empty() && (name.back() == ' ' || name.back() == '\r')) name.remove_suffix(1);
                    pending_name = std::string(name);
                    pending_span = {s.file, lines[li].first, lines[li].second};
                }
            }
        }
        if (!is_fence(line, info)) continue;
        // Find the closing fence.
        size_t close = li + 1;
        std::string_view dummy;
        while (close < lines.size() && !is_fence(t.substr(lines[close].first, lines[close].second - lines[close].first), dummy))
            ++close;
        uint32_t body_begin = li + 1 < lines.size() ? lines[li + 1].first : lines[li].second;
        uint32_t body_end = close < lines.size() ? lines[close].first : uint32_t(t.size());
        if (close >= lines.size())
            d.error({s.file, lines[li].first, lines[li].second}, "this code block is never closed with ```");
        if (info == "iheartla") {
            if (pending_name.empty()) {
                d.error({s.file, lines[li].first, lines[li].second},
                        "this iheartla block has no module name: put a line '❤: name' before it");
            } else if (!ModuleLibrary::is_file_name(pending_name)) {
                d.error(pending_span, bad_module_name(pending_name));
            } else if (auto it = by_name.find(pending_name); it != by_name.end()) {
                s.modules[it->second].ranges.push_back({body_begin, body_end});  // blocks with one name join
            } else {
                ModuleSource ms;
                ms.name = pending_name;
                ms.file = s.file;
                ms.ranges = {{body_begin, body_end}};
                ms.where = pending_span;
                ms.origin = "document";
                by_name[pending_name] = s.modules.size();
                s.modules.push_back(std::move(ms));
            }
            pending_name.clear();
        } else if (info == "scene") {
            if (have_scene) {
                d.error({s.file, lines[li].first, lines[li].second}, "a document can have only one scene block");
            } else {
                have_scene = true;
                SceneReader r(sm, d, s, s.file, body_begin);
                r.read(t.substr(body_begin, body_end - body_begin));
            }
        }
        li = close;
    }
    if (!have_scene) {
        uint32_t end = uint32_t(t.size());
        d.error({s.file, 0, std::min<uint32_t>(end, lines.empty() ? 0 : lines[0].second)},
                "the document has no scene block: add a ```scene block with at least one [[shapes]] entry");
    }
}

}  // namespace

bool load_scene(const std::string& path, SourceManager& sm, Diagnostics& d, SceneDesc& s) {
    std::string text, err;
    size_t before = d.error_count();
    if (!read_source_file(path, sm.total_bytes(), text, err)) {
        d.error_nospan(fmt::format("cannot read '{}': {}", path, err));
        return false;
    }
    s.path = path;
    s.file = sm.add_from_disk(path, std::move(text));
    std::string ext = fs::path(path).extension().string();
    // I♥IQ documents and single modules keep the thesis's look (linear output) unless their scene asks for more.
    s.thesis_look = ext == ".md" || ext == ".iql";
    if (ext == ".md") {
        read_document(sm, d, s);
    } else if (ext == ".iql") {
        // A module file alone: one instance of it at the origin, seen from the default camera.
        ModuleSource ms;
        ms.name = fs::path(path).stem().string();
        ms.file = s.file;
        ms.ranges = {{0, uint32_t(sm.text(s.file).size())}};
        ms.where = {s.file, 0, 1};
        ms.origin = "document";
        s.modules.push_back(ms);
        InstanceDesc inst;
        inst.type = ms.name;
        inst.type_span = ms.where;
        inst.span = ms.where;
        s.instances.push_back(std::move(inst));
        s.camera.position = {0, 0, -5};
        s.camera.target = {0, 0, 0};
    } else {
        SceneReader r(sm, d, s, s.file, 0);
        r.read(sm.text(s.file));
    }
    if (s.title.empty()) s.title = fs::path(path).stem().string();
    return d.error_count() == before;
}

}  // namespace iqc
