#include "ir/Parse.h"

#include <cstdlib>
#include <fmt/format.h>
#include <map>
#include <sstream>
#include <vector>

#include "sema/Builtins.h"

namespace iqc::ir {

namespace {

struct Failure {
    std::string what;
};

[[noreturn]] void fail(const std::string& what) { throw Failure{what}; }

// A cursor over one line.
struct Line {
    std::string s;
    size_t i = 0;

    void skip_spaces() {
        while (i < s.size() && s[i] == ' ') ++i;
    }
    bool at_end() {
        skip_spaces();
        return i >= s.size();
    }
    bool eat(const std::string& t) {
        skip_spaces();
        if (s.compare(i, t.size(), t) != 0) return false;
        i += t.size();
        return true;
    }
    void expect(const std::string& t) {
        if (!eat(t)) fail(fmt::format("expected '{}' at column {}", t, i + 1));
    }
    // A run of characters up to a space or one of `stops`.
    std::string word(const std::string& stops = "") {
        skip_spaces();
        size_t b = i;
        while (i < s.size() && s[i] != ' ' && stops.find(s[i]) == std::string::npos) ++i;
        if (b == i) fail(fmt::format("expected a word at column {}", i + 1));
        return s.substr(b, i - b);
    }
    double number() {
        skip_spaces();
        const char* begin = s.c_str() + i;
        char* end = nullptr;
        double v = std::strtod(begin, &end);
        if (end == begin) {
            if (eat("inf")) return INFINITY;
            if (eat("-inf")) return -INFINITY;
            if (eat("nan")) return NAN;
            fail(fmt::format("expected a number at column {}", i + 1));
        }
        i += size_t(end - begin);
        return v;
    }
    long long integer() { return (long long)number(); }
};

int superscript_number(Line& l) {
    static const char* digits[] = {"⁰", "¹", "²", "³", "⁴", "⁵", "⁶", "⁷", "⁸", "⁹"};
    int n = 0;
    bool any = false;
    for (bool more = true; more;) {
        more = false;
        for (int d = 0; d < 10; ++d)
            if (l.s.compare(l.i, std::string(digits[d]).size(), digits[d]) == 0) {
                l.i += std::string(digits[d]).size();
                n = n * 10 + d;
                any = more = true;
                break;
            }
    }
    return any ? n : -1;
}

Type parse_type(Line& l) {
    l.skip_spaces();
    Type t;
    if (l.eat("ℝ^(")) {
        int r = int(l.integer());
        l.expect("×");
        int c = int(l.integer());
        l.expect(")");
        t = Type::matrix(r, c);
    } else if (l.eat("ℝ")) {
        int n = superscript_number(l);
        t = n < 0 ? Type::scalar() : Type::vector(n);
    } else if (l.eat("ℤ")) {
        t = Type::integer();
    } else if (l.eat("condition")) {
        t = Type::boolean();
    } else if (l.eat("tuple(")) {
        int n = int(l.integer());
        l.expect(")");
        t = Type::tuple(n);
    } else {
        fail(fmt::format("expected a type at column {}", l.i + 1));
    }
    if (l.s.compare(l.i, 1, "[") == 0 && l.s.compare(l.i, 2, "[ ") != 0) {  // an array: T[N]
        ++l.i;
        int n = int(l.integer());
        l.expect("]");
        t = Type::array(t, n);
    }
    return t;
}

// ` ∈ [lo, hi]×[lo, hi]` (after a type), or nothing.
ValueBounds parse_bounds(Line& l) {
    ValueBounds b;
    b.input = false;
    if (!l.eat("∈")) return b;
    do {
        l.expect("[");
        b.lo.push_back(l.number());
        l.expect(",");
        b.hi.push_back(l.number());
        l.expect("]");
    } while (l.eat("×"));
    return b;
}

Op parse_op(const std::string& name) {
#define X(n, arity) \
    if (name == #n) return Op::n;
    IQC_IR_OPS(X)
#undef X
    fail("unknown operation '" + name + "'");
}

struct Parser {
    std::vector<std::string> lines;
    size_t at = 0;  // current line (0-based)
    Module& m;
    std::map<std::string, int> functions;

    int function_index(const std::string& name) {
        auto it = functions.find(name);
        if (it == functions.end()) fail("no function named '" + name + "'");
        return it->second;
    }

    void global(Line& l) {
        Global g;
        l.expect("global");
        l.expect("@");
        l.integer();
        g.name = l.word(":");
        l.expect(":");
        g.type = parse_type(l);
        std::string kind = l.word();
        if (kind == "parameter") g.kind = Global::Kind::Parameter;
        else if (kind == "constant") g.kind = Global::Kind::Constant;
        else if (kind == "prepared") g.kind = Global::Kind::Prepared;
        else fail("unknown global kind '" + kind + "'");
        if (g.kind != Global::Kind::Prepared) {
            l.expect("=");
            do g.value.push_back(l.number());
            while (l.eat(","));
        }
        g.bounds = parse_bounds(l);
        if (g.kind == Global::Kind::Prepared) g.bounds.input = true;
        if (l.eat(";")) {
            l.skip_spaces();
            g.comment = l.s.substr(l.i);
        }
        m.globals.push_back(std::move(g));
    }

    void header(Line& l, Function& f) {
        for (;;) {
            if (l.eat("entry ")) f.entry = true;
            else if (l.eat("inline ")) f.inline_hint = true;
            else break;
        }
        l.expect("function");
        f.name = l.word("(");
        f.glsl_name = f.name;
        l.expect("(");
        bool bounded = false;
        std::vector<ValueBounds> bounds;
        if (!l.eat(")")) {
            do {
                std::string name = l.word(":");
                l.expect(":");
                Type t = parse_type(l);
                ValueBounds b = parse_bounds(l);
                if (b.lo.empty()) b.input = true;
                bounded |= !b.input;
                f.params.push_back({name, t});
                bounds.push_back(std::move(b));
            } while (l.eat(","));
            l.expect(")");
        }
        if (bounded) f.param_bounds = std::move(bounds);
        l.expect("->");
        parse_type(l);
        l.expect("{");
    }

    Instr instruction(Line& l, size_t index) {
        Instr in;
        l.expect("%");
        if (size_t(l.integer()) != index) fail(fmt::format("instructions must be numbered in order (%{} expected)", index));
        l.expect("=");
        in.type = parse_type(l);
        in.op = parse_op(l.word());
        switch (in.op) {
            case Op::Const:
                do in.data.push_back(l.number());
                while (l.eat(","));
                break;
            case Op::Param:
                l.expect("#");
                in.aux = int(l.integer());
                l.word();
                break;
            case Op::Input: in.aux = l.word() == "time" ? 0 : 1; break;
            case Op::Loop:
                l.expect("from");
                in.data = {l.number()};
                in.aux = function_index(l.word());
                break;
            case Op::Member:
                l.expect(".");
                in.aux = int(l.integer());
                break;
            case Op::Global:
                l.expect("@");
                in.aux = int(l.integer());
                if (!l.at_end() && l.s[l.i] != '%' && l.s[l.i] != ';') l.word();
                break;
            case Op::Switch:
                while (l.eat("[")) {
                    in.data.push_back(l.number());
                    l.expect(",");
                    in.data.push_back(l.number());
                    l.expect(")");
                }
                break;
            case Op::Builtin: {
                std::string n = l.word();
                auto id = find_builtin(n);
                if (!id) fail("unknown built-in '" + n + "'");
                in.aux = *id;
                break;
            }
            case Op::Call: in.aux = function_index(l.word()); break;
            case Op::Extract:
            case Op::Element:
            case Op::Row:
            case Op::Column:
                l.expect("[");
                in.aux = int(l.integer());
                l.expect("]");
                break;
            case Op::Compare: {
                static const char* k[] = {"eq", "ne", "lt", "le", "gt", "ge"};
                std::string w = l.word();
                in.aux = -1;
                for (int c = 0; c < 6; ++c)
                    if (w == k[c]) in.aux = c;
                if (in.aux < 0) fail("unknown comparison '" + w + "'");
                break;
            }
            default: break;
        }
        if (!l.at_end() && l.s[l.i] == '%') {
            do {
                l.expect("%");
                in.args.push_back(ValueId(l.integer()));
            } while (l.eat(","));
        }
        if (l.eat(";")) in.name = l.word();
        if (!l.at_end()) fail(fmt::format("unexpected text at column {}", l.i + 1));
        return in;
    }

    void body(Function& f) {
        for (; at < lines.size(); ++at) {
            Line l{lines[at]};
            if (l.at_end()) continue;
            if (l.eat("}")) {
                ++at;
                return;
            }
            if (l.eat("lipschitz ")) {
                LipschitzSpec& s = f.lipschitz;
                s.object_fn = function_index(l.word());
                s.region = parse_bounds(l);
                l.expect("ball");
                s.ball = l.number();
                l.expect("group");
                s.group = int(l.integer());
                l.expect("declared");
                s.declared = l.number();
                s.trusted = l.word() == "trusted";
                l.expect("shape");
                s.shape = l.word();
                if (l.eat("factor")) {
                    l.expect("@");
                    s.factor_global = int(l.integer());
                }
            } else if (l.eat("return")) {
                l.expect("%");
                f.result = ValueId(l.integer());
            } else if (l.eat("output")) {
                std::string name = l.word("=");
                l.expect("=");
                l.expect("%");
                f.outputs.push_back({name, ValueId(l.integer())});
            } else {
                f.body.push_back(instruction(l, f.body.size()));
            }
        }
        fail("missing '}'");
    }

    void run() {
        // Function names first: calls and loops may name a function defined later.
        for (const auto& s : lines) {
            Line l{s};
            while (l.eat("entry ") || l.eat("inline ")) {}
            if (l.eat("function")) functions[l.word("(")] = int(functions.size());
        }
        m.functions.resize(functions.size());
        int next = 0;
        while (at < lines.size()) {
            Line l{lines[at]};
            if (l.at_end()) {
                ++at;
                continue;
            }
            if (l.eat("constant parameters")) {
                m.constant_parameters = true;
                ++at;
                continue;
            }
            if (l.s.compare(l.i, 7, "global ") == 0) {
                global(l);
                ++at;
                continue;
            }
            Function& f = m.functions[size_t(next++)];
            header(l, f);
            ++at;
            body(f);
        }
    }
};

// Drops `;` comments, except an instruction's `; name` (which follows an operand or a value).
std::string strip_comment(const std::string& line) {
    size_t semi = line.find(';');
    if (semi == std::string::npos) return line;
    std::string head = line.substr(0, semi);
    size_t first = head.find_first_not_of(' ');
    bool instruction = first != std::string::npos && head[first] == '%';
    bool global = first != std::string::npos && head.compare(first, 7, "global ") == 0;
    return (instruction || global) ? line : head;
}

}  // namespace

bool parse_module(const std::string& text, Module& out, std::string& error) {
    Parser p{{}, 0, out, {}};
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) p.lines.push_back(strip_comment(line));
    try {
        p.run();
    } catch (const Failure& f) {
        error = fmt::format("line {}: {}", p.at + 1, f.what);
        return false;
    }
    return true;
}

}  // namespace iqc::ir
