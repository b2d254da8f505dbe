#pragma once
// What the benchmarks share: comma-separated option lists, medians of repeated timings, and the
// short names of the real scans in ../shared/data.

#include <algorithm>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

namespace cuberille::bench {

/// "a,b,c" -> {"a", "b", "c"}.
inline std::vector<std::string> splitList(const std::string& s) {
    std::vector<std::string> out;
    std::stringstream in(s);
    for (std::string item; std::getline(in, item, ',');) out.push_back(item);
    return out;
}

inline double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    return v[v.size() / 2];
}

/// `bunny`, `dragon` (the full binary PLY) and `horse` name the scans under sourceDir/../shared/data;
/// anything else is taken as a path.
inline std::filesystem::path scanPath(const std::string& name, const std::filesystem::path& sourceDir) {
    const std::filesystem::path scans = sourceDir / ".." / "shared" / "data" / "scans";
    if (name == "bunny") return scans / "stanford-bunny" / "stanford-bunny.obj";
    if (name == "dragon") return scans / "stanford-dragon" / "dragon_vrip.binary.ply.gz";
    if (name == "horse") return scans / "cyberware-horse" / "horse.ply";
    return name;
}

}  // namespace cuberille::bench
