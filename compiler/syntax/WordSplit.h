// Splitting a run of letters into names, I♥LA's way: at each position the longest known multi-letter
// name starting there wins, otherwise one letter (with its combining marks) is one name.
//
// Linear in the length of the run plus the total length of the known names: an Aho–Corasick automaton
// (Aho & Corasick 1975, "Efficient string matching") over the known names written backwards, run over the
// run backwards, gives at each letter the longest known name that starts there. Checking every candidate
// substring instead was cubic (12,800 letters took 34 s).
#pragma once

#include <cstdint>
#include <memory>
#include <set>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

namespace iqc {

// Splits a letter run into letter units: a base letter and the combining marks after it
// ({byte offset, byte length} per unit).
std::vector<std::pair<size_t, size_t>> letter_units(const std::string& word);

class WordSplitter {
public:
    // `known`: the names a run may contain (names of one letter need not be listed).
    explicit WordSplitter(const std::set<std::string>& known);
    // For each letter unit of `word` (`units`: letter_units(word)), raises best[u] to the number of units
    // of the longest known name starting at unit u.
    void longest(const std::string& word, const std::vector<std::pair<size_t, size_t>>& units, std::vector<int>& best) const;
    // The automaton for a set of names used by many modules (the built-ins, a transform's imports), built once
    // per process and shared; thread-safe.
    static std::shared_ptr<const WordSplitter> shared(const std::set<std::string>& known);

private:
    struct Node {
        int fail = 0;     // the node of the longest proper suffix that is also in the automaton
        int longest = 0;  // units of the longest name that is a suffix of this node's string (0: none)
        int depth = 0;
        bool terminal = false;
        std::vector<std::pair<int, int>> children;  // symbol, node
    };
    std::vector<Node> nodes_;
    std::unordered_map<uint64_t, int> edges_;       // (node << 32 | symbol) -> node
    std::unordered_map<std::string, int> symbols_;  // letter unit -> symbol

    int child(int node, int symbol) const;
    int step(int node, int symbol) const;  // follows failure links; -1 symbols lead to the root
};

// The names `word` spells, as {byte offset, byte length} in `word`, in order: at each unit the longest
// name any of the splitters knows, else one letter.
std::vector<std::pair<size_t, size_t>> split_word(const std::string& word, const std::vector<const WordSplitter*>& splitters);

}  // namespace iqc
