#pragma once
// Small helpers shared by the text readers (.tri, PLY headers and ASCII bodies, OBJ, MTL).

#include <string_view>
#include <vector>

namespace cuberille::scene {

inline bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

/// The whitespace-separated words of one line into `out` (cleared first; a reader that keeps
/// `out` from line to line allocates nothing per line).
inline void splitWords(std::string_view line, std::vector<std::string_view>& out) {
    out.clear();
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isBlank(line[i])) ++i;
        size_t j = i;
        while (j < line.size() && !isBlank(line[j])) ++j;
        if (j > i) out.push_back(line.substr(i, j - i));
        i = j;
    }
}

/// The whitespace-separated words of one line (no allocation of the words themselves).
inline std::vector<std::string_view> splitWords(std::string_view line) {
    std::vector<std::string_view> out;
    splitWords(line, out);
    return out;
}

}  // namespace cuberille::scene
