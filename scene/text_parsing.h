#pragma once
// Small helpers shared by the text readers (.tri, PLY headers and ASCII bodies, OBJ, MTL).

#include <string_view>
#include <vector>

namespace cuberille::scene {

inline bool isBlank(char c) { return c == ' ' || c == '\t' || c == '\r'; }

/// The whitespace-separated words of one line (no allocation of the words themselves).
inline std::vector<std::string_view> splitWords(std::string_view line) {
    std::vector<std::string_view> out;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isBlank(line[i])) ++i;
        size_t j = i;
        while (j < line.size() && !isBlank(line[j])) ++j;
        if (j > i) out.push_back(line.substr(i, j - i));
        i = j;
    }
    return out;
}

}  // namespace cuberille::scene
