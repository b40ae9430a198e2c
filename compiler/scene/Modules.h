// The module library: finds a module's text by name and checks it once.
//
// Lookup order: modules added by the input (the scene's or document's own, then its includes), then
// `<dir>/<name>.iql` in the search directories (the input's folder), then the standard library
// (stdlib/, embedded in the binary). The same name added twice is an error naming both places; a module
// that imports itself, directly or not, is an import cycle; imports nest at most limits::kMaxImportDepth deep.
// Names are never paths: a name with a folder in it (`../x`, `/tmp/x`) is not looked up in the file system.
#pragma once

#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "scene/Scene.h"
#include "ir/Eval.h"
#include "sema/Check.h"

namespace iqc {

class ModuleLibrary {
public:
    ModuleLibrary(SourceManager& sm, Diagnostics& d, std::vector<std::string> search_dirs = {})
        : sm_(sm), d_(d), dirs_(std::move(search_dirs)) {}

    // Registers a module defined by the input (reports a name defined twice).
    void add(const ModuleSource& m);
    // The checked module of that name, or null when there is none (unknown names are the caller's to report).
    const CheckedModule* get(const std::string& name, Span where);
    // Parses and checks a module's text; `transform` gives it the implicit transformation imports.
    // `given` types parameters from outside (binding symbolic sizes and sequence lengths) and defines its
    // function parameters (f: ℝ → ℝ).
    std::unique_ptr<CheckedModule> parse_check(const ModuleSource& src, const std::string& name, bool transform,
                                               const std::map<std::string, Type>& given_types = {},
                                               const std::map<std::string, std::shared_ptr<const ast::Module>>& given_functions = {});
    // Checks the named module afresh (not cached) with parameter types known from outside; null if none.
    std::unique_ptr<CheckedModule> check_with(const std::string& name, const std::map<std::string, Type>& given_types,
                                              const std::map<std::string, std::shared_ptr<const ast::Module>>& given_functions = {});
    // The named module checked with some of its sequence parameters of other lengths (`lengths`: name ->
    // element count), for an instance whose override has that many elements: checked once per combination
    // and kept (null where the module is unknown). Its IR function is named apart (CheckedModule::ir_name).
    const CheckedModule* variant(const std::string& name, const std::map<std::string, int>& lengths);
    // Parses `NAME(params) = expression` given for a function parameter (iqc eval --set 'f(x)=x²').
    std::shared_ptr<const ast::Module> parse_function(const ModuleSource& src);
    // Every module name that lookup can find, for "did you mean".
    std::vector<std::string> names() const;

    // Whether a name can be looked up as `<dir>/<name>.iql`: a plain file name, no folders, no leading dot.
    static bool is_file_name(const std::string& name);

    // The names a scene transform imports without saying so.
    static const std::vector<std::pair<std::string, std::string>>& transform_imports();

    // The value of a constant expression written as text (a default such as √2, a `--set` value, an
    // override): parsed and checked as a module of its own (trigonometry imported), lowered, run through
    // the pass pipeline and evaluated — the one meaning every value gets. `name` names it in diagnostics.
    // Returns nullopt after reporting to `d` when it is not a constant number, vector or matrix.
    static std::optional<ir::Value> evaluate_constant(const std::string& name, const std::string& text, SourceManager& sm,
                                                      Diagnostics& d);

private:
    SourceManager& sm_;
    Diagnostics& d_;
    std::vector<std::string> dirs_;
    std::map<std::string, const ModuleSource*> registry_;
    std::vector<std::unique_ptr<ModuleSource>> owned_;
    std::map<std::string, std::unique_ptr<CheckedModule>> checked_;
    std::map<std::pair<std::string, std::map<std::string, int>>, std::unique_ptr<CheckedModule>> variants_;
    std::set<std::string> in_progress_;
    bool constants_ = false;  // checking a constant expression (trigonometry is imported)

    // `where`: where the name was written (for a file that exists but cannot be read); may be empty.
    const ModuleSource* find_source(const std::string& name, Span where);
};

}  // namespace iqc
