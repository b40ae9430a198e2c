#include "syntax/WordSplit.h"

#include <algorithm>
#include <map>
#include <mutex>

#include "source/Source.h"

namespace iqc {

std::vector<std::pair<size_t, size_t>> letter_units(const std::string& w) {
    std::vector<std::pair<size_t, size_t>> units;  // byte offset, length
    size_t i = 0;
    while (i < w.size()) {
        size_t b = i;
        utf8::decode(w, i);
        while (i < w.size()) {
            size_t j = i;
            char32_t c = utf8::decode(w, j);
            if (!utf8::is_combining(c)) break;
            i = j;
        }
        units.push_back({b, i - b});
    }
    return units;
}

int WordSplitter::child(int node, int symbol) const {
    auto it = edges_.find((uint64_t(uint32_t(node)) << 32) | uint32_t(symbol));
    return it == edges_.end() ? -1 : it->second;
}

int WordSplitter::step(int node, int symbol) const {
    if (symbol < 0) return 0;
    while (true) {
        int c = child(node, symbol);
        if (c >= 0) return c;
        if (node == 0) return 0;
        node = nodes_[size_t(node)].fail;
    }
}

WordSplitter::WordSplitter(const std::set<std::string>& known) {
    nodes_.emplace_back();
    for (const std::string& name : known) {
        auto units = letter_units(name);
        if (units.size() < 2) continue;
        int node = 0;
        for (size_t k = units.size(); k-- > 0;) {  // the name backwards
            std::string unit = name.substr(units[k].first, units[k].second);
            int symbol = symbols_.emplace(unit, int(symbols_.size())).first->second;
            int next = child(node, symbol);
            if (next < 0) {
                next = int(nodes_.size());
                nodes_.emplace_back();
                nodes_.back().depth = nodes_[size_t(node)].depth + 1;
                nodes_[size_t(node)].children.push_back({symbol, next});
                edges_[(uint64_t(uint32_t(node)) << 32) | uint32_t(symbol)] = next;
            }
            node = next;
        }
        nodes_[size_t(node)].terminal = true;
    }
    // Failure links breadth first: a node's fail is found from its parent's.
    std::vector<int> queue = {0};
    for (size_t q = 0; q < queue.size(); ++q) {
        int v = queue[q];
        for (auto [symbol, c] : nodes_[size_t(v)].children) {
            int f = v == 0 ? 0 : step(nodes_[size_t(v)].fail, symbol);
            Node& n = nodes_[size_t(c)];
            n.fail = f == c ? 0 : f;
            n.longest = n.terminal ? n.depth : nodes_[size_t(n.fail)].longest;
            queue.push_back(c);
        }
    }
}

void WordSplitter::longest(const std::string& word, const std::vector<std::pair<size_t, size_t>>& units,
                           std::vector<int>& best) const {
    int state = 0;
    for (size_t u = units.size(); u-- > 0;) {  // the automaton reads backwards
        auto it = symbols_.find(word.substr(units[u].first, units[u].second));
        state = step(state, it == symbols_.end() ? -1 : it->second);
        best[u] = std::max(best[u], nodes_[size_t(state)].longest);
    }
}

std::shared_ptr<const WordSplitter> WordSplitter::shared(const std::set<std::string>& known) {
    static std::mutex mu;
    static std::map<std::set<std::string>, std::shared_ptr<const WordSplitter>> cache;
    std::lock_guard<std::mutex> lock(mu);
    auto it = cache.find(known);
    if (it != cache.end()) return it->second;
    if (cache.size() >= 8) cache.clear();  // a few distinct sets exist per process; never grow without bound
    auto splitter = std::make_shared<const WordSplitter>(known);
    cache.emplace(known, splitter);
    return splitter;
}

std::vector<std::pair<size_t, size_t>> split_word(const std::string& word, const std::vector<const WordSplitter*>& splitters) {
    auto units = letter_units(word);
    std::vector<int> best(units.size(), 0);
    for (const WordSplitter* s : splitters) s->longest(word, units, best);
    std::vector<std::pair<size_t, size_t>> pieces;
    for (size_t u = 0; u < units.size();) {
        size_t n = std::max<size_t>(1, size_t(best[u]));
        size_t b = units[u].first;
        size_t e = units[u + n - 1].first + units[u + n - 1].second;
        pieces.push_back({b, e - b});
        u += n;
    }
    return pieces;
}

}  // namespace iqc
