// Source files, spans and diagnostics.
//
// Every other pass refers to text by Span (a file and a byte range). Diagnostics are collected, never
// thrown, and rendered GCC-style: `file:line:col: error: message`, the source line, and a caret line
// underlining the span. Columns count Unicode code points (combining marks take no column), so carets
// line up under math such as `N̂`.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace iqc {

using FileId = uint32_t;

struct Span {
    FileId file = 0;
    uint32_t begin = 0;  // byte offset
    uint32_t end = 0;    // byte offset, exclusive
    bool valid() const { return end >= begin && (begin != 0 || end != 0 || file != 0); }
    static Span join(Span a, Span b) { return {a.file, std::min(a.begin, b.begin), std::max(a.end, b.end)}; }
};

struct LineCol {
    uint32_t line = 1;  // 1-based
    uint32_t col = 1;   // 1-based, in code points
};

class SourceManager {
public:
    // Adds a file with the given display name and contents.
    FileId add(std::string name, std::string text);
    // Adds a file read from disk at `path` (its display name): it is one of the files the compile depends on
    // (disk_files(), what `iqc --depfile` lists).
    FileId add_from_disk(std::string path, std::string text);
    // Adds text that sits inside another file starting at byte `offset` (e.g. an escaped TOML string whose
    // text differs from the file's bytes): diagnostics report the outer file's name and the line where the
    // string starts, plus the line within the string.
    FileId add_embedded(std::string name, std::string text, FileId outer, uint32_t outer_offset);
    // The same, with each byte's offset in the outer file (`outer_map`: text.size() + 1 entries, the last where the
    // text ends): a TOML string with escapes (`"shape\nD = …"`), whose lines are not the file's. Diagnostics then
    // point into the outer file itself (display).
    FileId add_embedded(std::string name, std::string text, FileId outer, std::vector<uint32_t> outer_map);
    // Where a span is shown: for an embedded file with an offset map, the span in its outer file; else itself.
    Span display(Span s) const;

    const std::string& name(FileId f) const { return files_[f].name; }
    std::string_view text(FileId f) const { return files_[f].text; }
    LineCol line_col(FileId f, uint32_t offset) const;
    std::string_view line_text(FileId f, uint32_t line) const;  // without the newline
    std::string_view slice(Span s) const { return text(s.file).substr(s.begin, s.end - s.begin); }
    // Display position: for embedded files, the position translated into the outer file.
    std::string location(Span s) const;
    size_t size() const { return files_.size(); }
    // Bytes of every file added so far (for the limit on what one compile reads).
    size_t total_bytes() const { return total_bytes_; }
    // The paths of the files added by add_from_disk, in the order they were read, each once.
    std::vector<std::string> disk_files() const;

private:
    struct File {
        std::string name, text;
        std::vector<uint32_t> line_starts;
        bool embedded = false;
        bool from_disk = false;
        FileId outer = 0;
        uint32_t outer_offset = 0;
        std::vector<uint32_t> outer_map;  // per byte of text (and its end): the offset in `outer` (empty: none)
    };
    std::vector<File> files_;
    size_t total_bytes_ = 0;
    struct ColumnCache {
        FileId file = FileId(-1);
        uint32_t line_start = 0, offset = 0, col = 1;
    };
    mutable ColumnCache cache_;  // line_col's last answer
};

// Reads a source file for a compile that has already read `already` bytes: regular files only (a pipe,
// a device or a directory is refused at once, never waited on), at most limits::kMaxFileBytes each and
// limits::kMaxTotalBytes in all. False with `err` saying why ("it is not a regular file", ...).
bool read_source_file(const std::string& path, size_t already, std::string& out, std::string& err);

enum class Severity { Error, Warning, Note };

struct Diagnostic {
    Severity severity = Severity::Error;
    Span span;
    bool has_span = true;
    std::string message;
    std::vector<Diagnostic> notes;
};

class Diagnostics {
public:
    explicit Diagnostics(const SourceManager& sm) : sm_(sm) {}
    Diagnostic& error(Span s, std::string msg);
    Diagnostic& warning(Span s, std::string msg);
    Diagnostic& error_nospan(std::string msg);
    static void note(Diagnostic& d, Span s, std::string msg);

    bool has_errors() const { return errors_ > 0; }
    size_t error_count() const { return errors_; }
    const std::vector<Diagnostic>& all() const { return list_; }
    // Renders every diagnostic, in the order reported.
    std::string render() const;
    std::string render(const Diagnostic& d) const;
    const SourceManager& sources() const { return sm_; }

    // Diagnostics kept and rendered: past this many, the rest are only counted (render() says how many), so
    // hostile input cannot print megabytes of them.
    static constexpr size_t kMaxKept = 200;

private:
    Diagnostic& add(Diagnostic d);
    const SourceManager& sm_;
    std::vector<Diagnostic> list_;
    Diagnostic overflow_;  // where a diagnostic past kMaxKept goes (its notes too)
    Diagnostic duplicate_;  // where a diagnostic already reported goes (its notes too)
    size_t errors_ = 0, dropped_ = 0;
};

// A user's name or path for a one-line message: newline and tab as \n and \t, other control characters as \xNN.
std::string escape_controls(std::string_view s);

// UTF-8 helpers shared by the lexer and the renderer.
namespace utf8 {
// Decodes one code point at text[i]; advances i. Invalid bytes decode as U+FFFD.
char32_t decode(std::string_view text, size_t& i);
void append(std::string& out, char32_t c);
bool is_combining(char32_t c);
// An invisible formatting or separator character: zero-width spaces and joiners, bidirectional embeddings,
// overrides and isolates (Trojan Source), line and paragraph separators, the BOM, the soft hyphen.
bool is_invisible(char32_t c);
// Display width of a string in columns (combining marks are 0, everything else 1).
size_t width(std::string_view s);
}  // namespace utf8

}  // namespace iqc
