#pragma once
// File names as the tool recognises formats by them: case-insensitively, so `DRAGON.PLY.GZ` is a
// gzip-compressed PLY like `dragon.ply.gz`.

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>
#include <string_view>

namespace cuberille::scene {

inline std::string lowercase(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

/// Whether the file name ends with suffix (lower case, e.g. ".ply.gz"), ignoring case.
inline bool fileNameEndsWith(const std::filesystem::path& path, std::string_view suffix) {
    const std::string n = lowercase(path.filename().string());
    return n.size() >= suffix.size() && n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// The path's last extension in lower case (".exr"), empty when it has none.
inline std::string lowerExtension(const std::filesystem::path& path) { return lowercase(path.extension().string()); }

}  // namespace cuberille::scene
