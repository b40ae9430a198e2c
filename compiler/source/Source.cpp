#include "source/Source.h"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fcntl.h>
#include <fmt/format.h>
#include <sys/stat.h>
#include <unistd.h>

#include "source/Limits.h"

namespace iqc {

namespace utf8 {

char32_t decode(std::string_view t, size_t& i) {
    unsigned char c = static_cast<unsigned char>(t[i]);
    auto cont = [&](size_t k) -> int {
        if (i + k >= t.size()) return -1;
        unsigned char b = static_cast<unsigned char>(t[i + k]);
        return (b & 0xC0) == 0x80 ? (b & 0x3F) : -1;
    };
    if (c < 0x80) { i += 1; return c; }
    // Well-formed UTF-8 only (RFC 3629): an overlong form (C0 AF for '/'), a surrogate (ED A0 80) or a code point
    // past U+10FFFF is one invalid byte, like any other.
    if ((c & 0xE0) == 0xC0) {
        int b1 = cont(1);
        char32_t cp = b1 >= 0 ? char32_t(((c & 0x1F) << 6) | b1) : 0;
        if (b1 >= 0 && cp >= 0x80) { i += 2; return cp; }
    } else if ((c & 0xF0) == 0xE0) {
        int b1 = cont(1), b2 = cont(2);
        char32_t cp = b1 >= 0 && b2 >= 0 ? char32_t(((c & 0x0F) << 12) | (b1 << 6) | b2) : 0;
        if (b1 >= 0 && b2 >= 0 && cp >= 0x800 && (cp < 0xD800 || cp > 0xDFFF)) { i += 3; return cp; }
    } else if ((c & 0xF8) == 0xF0) {
        int b1 = cont(1), b2 = cont(2), b3 = cont(3);
        char32_t cp = b1 >= 0 && b2 >= 0 && b3 >= 0 ? char32_t(((c & 0x07) << 18) | (b1 << 12) | (b2 << 6) | b3) : 0;
        if (b1 >= 0 && b2 >= 0 && b3 >= 0 && cp >= 0x10000 && cp <= 0x10FFFF) {
            i += 4;
            return cp;
        }
    }
    i += 1;
    return 0xFFFD;
}

void append(std::string& out, char32_t c) {
    if (c < 0x80) {
        out += char(c);
    } else if (c < 0x800) {
        out += char(0xC0 | (c >> 6));
        out += char(0x80 | (c & 0x3F));
    } else if (c < 0x10000) {
        out += char(0xE0 | (c >> 12));
        out += char(0x80 | ((c >> 6) & 0x3F));
        out += char(0x80 | (c & 0x3F));
    } else {
        out += char(0xF0 | (c >> 18));
        out += char(0x80 | ((c >> 12) & 0x3F));
        out += char(0x80 | ((c >> 6) & 0x3F));
        out += char(0x80 | (c & 0x3F));
    }
}

bool is_invisible(char32_t c) {
    return c == 0xAD || c == 0x61C || c == 0x115F || c == 0x1160 || c == 0x180E || (c >= 0x200B && c <= 0x200F) ||
           (c >= 0x2028 && c <= 0x202E) || (c >= 0x2060 && c <= 0x2064) || (c >= 0x2066 && c <= 0x206F) || c == 0x3164 ||
           (c >= 0xFE00 && c <= 0xFE0F) || c == 0xFEFF || c == 0xFFA0 || (c >= 0xFFF9 && c <= 0xFFFB) ||
           (c >= 0xE0000 && c <= 0xE0FFF);
}

bool is_combining(char32_t c) {
    return (c >= 0x0300 && c <= 0x036F) || (c >= 0x1AB0 && c <= 0x1AFF) || (c >= 0x1DC0 && c <= 0x1DFF) ||
           (c >= 0x20D0 && c <= 0x20FF) || (c >= 0xFE20 && c <= 0xFE2F);
}

size_t width(std::string_view s) {
    size_t w = 0;
    for (size_t i = 0; i < s.size();) {
        if (static_cast<unsigned char>(s[i]) < 0x80) {  // ASCII: one column
            ++w;
            ++i;
            continue;
        }
        char32_t c = decode(s, i);
        if (!is_combining(c)) ++w;
    }
    return w;
}

}  // namespace utf8

static std::vector<uint32_t> compute_line_starts(std::string_view text) {
    std::vector<uint32_t> starts{0};
    for (uint32_t i = 0; i < text.size(); ++i)
        if (text[i] == '\n') starts.push_back(i + 1);
    return starts;
}

FileId SourceManager::add(std::string name, std::string text) {
    File f;
    f.name = std::move(name);
    f.text = std::move(text);
    f.line_starts = compute_line_starts(f.text);
    total_bytes_ += f.text.size();
    files_.push_back(std::move(f));
    return FileId(files_.size() - 1);
}

FileId SourceManager::add_from_disk(std::string path, std::string text) {
    FileId id = add(std::move(path), std::move(text));
    files_[id].from_disk = true;
    return id;
}

std::vector<std::string> SourceManager::disk_files() const {
    std::vector<std::string> out;
    for (const auto& f : files_)
        if (f.from_disk && std::find(out.begin(), out.end(), f.name) == out.end()) out.push_back(f.name);
    return out;
}

FileId SourceManager::add_embedded(std::string name, std::string text, FileId outer, uint32_t outer_offset) {
    FileId id = add(std::move(name), std::move(text));
    files_[id].embedded = true;
    files_[id].outer = outer;
    files_[id].outer_offset = outer_offset;
    return id;
}

FileId SourceManager::add_embedded(std::string name, std::string text, FileId outer, std::vector<uint32_t> outer_map) {
    uint32_t at = outer_map.empty() ? 0 : outer_map.front();
    FileId id = add_embedded(std::move(name), std::move(text), outer, at);
    if (outer_map.size() == files_[id].text.size() + 1) files_[id].outer_map = std::move(outer_map);
    return id;
}

Span SourceManager::display(Span s) const {
    if (s.file >= files_.size()) return s;
    const File& f = files_[s.file];
    if (!f.embedded || f.outer_map.empty()) return s;
    auto at = [&](uint32_t o) { return f.outer_map[std::min<size_t>(o, f.outer_map.size() - 1)]; };
    uint32_t b = at(s.begin), e = at(s.end);
    return display(Span{f.outer, b, std::max(b, e)});
}

bool read_source_file(const std::string& path, size_t already, std::string& out, std::string& err) {
    // O_NONBLOCK: opening a named pipe must not wait for a writer; the mode is checked before any read.
    int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        err = std::strerror(errno);
        return false;
    }
    struct stat st {};
    size_t budget = already >= limits::kMaxTotalBytes ? 0 : limits::kMaxTotalBytes - already;
    size_t cap = std::min(limits::kMaxFileBytes, budget);
    bool ok = false;
    if (::fstat(fd, &st) != 0) {
        err = std::strerror(errno);
    } else if (S_ISDIR(st.st_mode)) {
        err = "it is a directory";
    } else if (!S_ISREG(st.st_mode)) {
        err = "it is not a regular file (iqc reads no pipes or devices)";
    } else {
        out.clear();
        char buf[65536];
        ok = true;
        while (true) {
            ssize_t n = ::read(fd, buf, sizeof buf);
            if (n < 0 && errno == EINTR) continue;
            if (n < 0) {
                err = std::strerror(errno);
                ok = false;
                break;
            }
            if (n == 0) break;
            if (out.size() + size_t(n) > cap) {
                err = cap < limits::kMaxFileBytes
                          ? fmt::format("the files of this compile would exceed {} MiB in all", limits::kMaxTotalBytes >> 20)
                          : fmt::format("it is larger than {} MiB", limits::kMaxFileBytes >> 20);
                ok = false;
                break;
            }
            out.append(buf, size_t(n));
        }
    }
    ::close(fd);
    if (!ok) out.clear();
    return ok;
}

LineCol SourceManager::line_col(FileId f, uint32_t offset) const {
    const File& file = files_[f];
    offset = std::min<uint32_t>(offset, uint32_t(file.text.size()));
    auto it = std::upper_bound(file.line_starts.begin(), file.line_starts.end(), offset);
    uint32_t line = uint32_t(it - file.line_starts.begin());
    uint32_t start = file.line_starts[line - 1];
    // Columns along one long line are asked for in order (diagnostics of a 10 MB one-liner): continue from
    // the last answer on the same line instead of counting from its start each time.
    uint32_t from = start, col = 1;
    if (cache_.file == f && cache_.line_start == start && cache_.offset <= offset && cache_.offset >= start) {
        from = cache_.offset;
        col = cache_.col;
    }
    col += uint32_t(utf8::width(std::string_view(file.text).substr(from, offset - from)));
    cache_ = {f, start, offset, col};
    return {line, col};
}

std::string_view SourceManager::line_text(FileId f, uint32_t line) const {
    const File& file = files_[f];
    if (line == 0 || line > file.line_starts.size()) return {};
    uint32_t start = file.line_starts[line - 1];
    uint32_t end = line < file.line_starts.size() ? file.line_starts[line] - 1 : uint32_t(file.text.size());
    std::string_view v = std::string_view(file.text).substr(start, end - start);
    if (!v.empty() && v.back() == '\r') v.remove_suffix(1);
    return v;
}

std::string SourceManager::location(Span s) const {
    const File& file = files_[s.file];
    LineCol lc = line_col(s.file, s.begin);
    if (file.embedded) {
        LineCol outer = line_col(file.outer, file.outer_offset);
        uint32_t line = outer.line + lc.line - 1;
        uint32_t col = lc.line == 1 ? outer.col + lc.col - 1 : lc.col;
        return fmt::format("{}:{}:{}", files_[file.outer].name, line, col);
    }
    return fmt::format("{}:{}:{}", file.name, lc.line, lc.col);
}

Diagnostic& Diagnostics::add(Diagnostic d) {
    // The same message at the same place once: a checker that tries two readings of `a(sin(r), 0, 0)` (a call, a
    // product) checked the arguments twice and said "'sin' needs an import" twice. (Its notes go with the copy.)
    for (const Diagnostic& o : list_)
        if (o.severity == d.severity && o.has_span == d.has_span && o.message == d.message &&
            (!d.has_span || (o.span.file == d.span.file && o.span.begin == d.span.begin && o.span.end == d.span.end))) {
            duplicate_ = std::move(d);
            return duplicate_;
        }
    if (d.severity == Severity::Error) ++errors_;
    if (list_.size() >= kMaxKept) {
        ++dropped_;
        overflow_ = std::move(d);
        return overflow_;
    }
    list_.push_back(std::move(d));
    return list_.back();
}

Diagnostic& Diagnostics::error(Span s, std::string msg) { return add({Severity::Error, s, true, std::move(msg), {}}); }

Diagnostic& Diagnostics::warning(Span s, std::string msg) { return add({Severity::Warning, s, true, std::move(msg), {}}); }

Diagnostic& Diagnostics::error_nospan(std::string msg) { return add({Severity::Error, {}, false, std::move(msg), {}}); }

void Diagnostics::note(Diagnostic& d, Span s, std::string msg) {
    d.notes.push_back({Severity::Note, s, true, std::move(msg), {}});
}

static const char* severity_name(Severity s) {
    switch (s) {
        case Severity::Error: return "error";
        case Severity::Warning: return "warning";
        case Severity::Note: return "note";
    }
    return "error";
}

std::string escape_controls(std::string_view s) {
    std::string out;
    for (char c : s) {
        unsigned char u = static_cast<unsigned char>(c);
        if (c == '\n') out += "\\n";
        else if (c == '\t') out += "\\t";
        else if (u < 0x20 || u == 0x7f) out += fmt::format("\\x{:02x}", u);
        else out += c;
    }
    return out;
}

// Text as shown in a diagnostic: control characters (a NUL, an escape sequence) become their visible
// pictures (U+2400 + c, ␡ for DEL), one column each like the byte they stand for; tabs and (in messages)
// newlines stay.
// Invisible formatting characters (a bidirectional override would reorder the terminal's line: Trojan Source)
// are shown as U+FFFD in a source line (one column, as counted for the caret) and spelled <U+202E> in a
// message, where a stray combining mark is spelled too (it would combine with the quote before it).
static std::string printable(std::string_view text, bool keep_newlines) {
    std::string out;
    out.reserve(text.size());
    for (size_t i = 0; i < text.size();) {
        unsigned char c = static_cast<unsigned char>(text[i]);
        if (c < 0x80) {
            if ((c < 0x20 && c != '\t' && !(keep_newlines && c == '\n')) || c == 0x7F) utf8::append(out, c == 0x7F ? 0x2421 : 0x2400 + c);
            else out += char(c);
            ++i;
            continue;
        }
        size_t from = i;
        char32_t cp = utf8::decode(text, i);
        if (i == from) ++i;  // (never stalls)
        const bool odd_space = cp == 0xA0 || (cp >= 0x2000 && cp <= 0x200A) || cp == 0x202F || cp == 0x205F || cp == 0x3000;
        if (utf8::is_invisible(cp) || (odd_space && !keep_newlines)) {  // (a space that is not ' ' looks like one)
            if (keep_newlines) out += fmt::format("<U+{:04X}>", unsigned(cp));
            else utf8::append(out, 0xFFFD);
        } else if (keep_newlines && (odd_space || (utf8::is_combining(cp) && (from == 0 || text[from - 1] == '\'' || text[from - 1] == ' ')))) {
            out += fmt::format("<U+{:04X}>", unsigned(cp));  // a space that is not one, a mark that would combine
        } else if (cp == 0xFFFD && i - from == 1) {
            // A byte that is not UTF-8: spelled in a message, the replacement character in a source line.
            if (keep_newlines) out += fmt::format("<byte 0x{:02X}>", unsigned(c));
            else utf8::append(out, 0xFFFD);
        } else {
            out.append(text.substr(from, i - from));
        }
    }
    return out;
}

std::string Diagnostics::render(const Diagnostic& given) const {
    std::string out;
    Diagnostic d = given;
    if (d.has_span) d.span = sm_.display(d.span);  // a TOML string with escapes: the file's own line
    if (!d.has_span) {
        out += fmt::format("iqc: {}: {}\n", severity_name(d.severity), printable(d.message, true));
    } else {
        out += fmt::format("{}: {}: {}\n", sm_.location(d.span), severity_name(d.severity), printable(d.message, true));
        LineCol b = sm_.line_col(d.span.file, d.span.begin);
        LineCol e = sm_.line_col(d.span.file, d.span.end);
        std::string_view line = sm_.line_text(d.span.file, b.line);
        size_t start = b.col - 1;
        size_t len = (e.line == b.line && e.col > b.col) ? e.col - b.col : 1;
        // A long line (a 10 MB one-liner) is shown as a window of about 480 bytes around the caret, with …
        // where it is cut, so each diagnostic stays a few hundred bytes.
        std::string prefix, suffix;
        if (line.size() > 640 && e.line == b.line) {
            std::string_view text = sm_.text(d.span.file);
            size_t idx = size_t(d.span.begin) - size_t(line.data() - text.data());
            size_t end_idx = std::min(line.size(), size_t(d.span.end) - size_t(line.data() - text.data()));
            size_t from = idx > 160 ? idx - 160 : 0;
            while (from < line.size() && (static_cast<unsigned char>(line[from]) & 0xC0) == 0x80) ++from;
            size_t to = std::min(line.size(), from + 480);
            while (to < line.size() && (static_cast<unsigned char>(line[to]) & 0xC0) == 0x80) --to;
            if (from > 0) prefix = "…";
            if (to < line.size()) suffix = "…";
            start = utf8::width(line.substr(from, idx - from)) + (from > 0 ? 1 : 0);
            len = std::max<size_t>(1, utf8::width(line.substr(idx, std::min(end_idx, to) - std::min(idx, std::min(end_idx, to)))));
            line = line.substr(from, to - from);
        }
        out += fmt::format("  {}{}{}\n", prefix, printable(line, false), suffix);
        size_t line_width = utf8::width(line) + (prefix.empty() ? 0 : 1);
        if (e.line != b.line) len = std::max<size_t>(1, line_width > start ? line_width - start : 1);
        std::string marks(len, '~');
        marks[0] = '^';
        // The caret's indent keeps the line's tabs (a terminal widens a tab to its next stop in both lines alike):
        // with spaces only, a caret under a line indented by tabs pointed columns to the left of its place.
        std::string indent = prefix.empty() ? "" : " ";
        for (size_t i = 0; indent.size() < start && i < line.size();) {
            const size_t from = i;
            char32_t cp = utf8::decode(line, i);
            if (i == from) ++i;  // (never stalls)
            if (utf8::is_combining(cp)) continue;
            indent += cp == U'\t' ? '\t' : ' ';
        }
        indent.resize(std::max(indent.size(), start), ' ');
        out += fmt::format("  {}{}\n", indent, marks);
    }
    for (const auto& n : d.notes) out += render(n);
    return out;
}

std::string Diagnostics::render() const {
    std::string out;
    for (const auto& d : list_) out += render(d);
    if (dropped_ > 0)
        out += fmt::format("iqc: note: {} more diagnostic{} not shown ({} error{} in all)\n", dropped_, dropped_ == 1 ? "" : "s",
                           errors_, errors_ == 1 ? "" : "s");
    return out;
}

}  // namespace iqc
