#pragma once
// PLY files that tests write themselves: a bumpy grid surface described either as a face list
// or as triangle strips in the variants scanners' writers use (one strip per row separated by
// -1 restarts, one strip per instance, rows stitched by zero-area joins).

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace cuberille::testing {

enum class PlyConnectivity { FaceList, StripsWithRestarts, StripPerInstance, StitchedStrip };

/// A grid of columns x rows quads over [0, 1]², heights a smooth bump. Vertex (r, c) is r * (columns + 1) + c.
struct PlyGrid {
    int columns = 6, rows = 4;

    int vertex(int r, int c) const { return r * (columns + 1) + c; }
    int vertexCount() const { return (rows + 1) * (columns + 1); }

    // Each quad as the two triangles a strip along its row gives, written out independently:
    // (r,c) (r+1,c) (r,c+1) and (r,c+1) (r+1,c) (r+1,c+1), both of one winding.
    std::vector<std::vector<int>> faces() const {
        std::vector<std::vector<int>> f;
        for (int r = 0; r < rows; ++r)
            for (int c = 0; c < columns; ++c) {
                f.push_back({vertex(r, c), vertex(r + 1, c), vertex(r, c + 1)});
                f.push_back({vertex(r, c + 1), vertex(r + 1, c), vertex(r + 1, c + 1)});
            }
        return f;
    }
    // The row strips (r,0) (r+1,0) (r,1) (r+1,1) ... joined as the variant asks.
    std::vector<std::vector<int>> strips(PlyConnectivity kind) const {
        std::vector<std::vector<int>> rowStrips;
        for (int r = 0; r < rows; ++r) {
            std::vector<int> s;
            for (int c = 0; c <= columns; ++c) s.insert(s.end(), {vertex(r, c), vertex(r + 1, c)});
            rowStrips.push_back(s);
        }
        if (kind == PlyConnectivity::StripPerInstance) return rowStrips;
        std::vector<int> one;
        for (size_t i = 0; i < rowStrips.size(); ++i) {
            if (i > 0 && kind == PlyConnectivity::StripsWithRestarts) one.push_back(-1);
            // Stitching repeats the last vertex and the next strip's first: four zero-area
            // triangles, and the next strip starts at an even place, its winding unchanged.
            if (i > 0 && kind == PlyConnectivity::StitchedStrip) one.insert(one.end(), {one.back(), rowStrips[i][0]});
            one.insert(one.end(), rowStrips[i].begin(), rowStrips[i].end());
        }
        return {one};
    }

    float height(int r, int c) const {
        const float x = float(c) / float(columns) - 0.5f, y = float(r) / float(rows) - 0.5f;
        return 0.3f * std::exp(-6.0f * (x * x + y * y));
    }

    /// The file, ASCII or binary little-endian.
    std::string ply(PlyConnectivity kind, bool binary) const {
        const bool faceList = kind == PlyConnectivity::FaceList;
        const std::vector<std::vector<int>> lists = faceList ? faces() : strips(kind);
        std::string s = "ply\nformat " + std::string(binary ? "binary_little_endian" : "ascii") + " 1.0\n";
        s += "element vertex " + std::to_string(vertexCount()) + "\nproperty float x\nproperty float y\nproperty float z\n";
        s += std::string(faceList ? "element face " : "element tristrips ") + std::to_string(lists.size()) + "\n";
        s += faceList ? "property list uchar int vertex_indices\n" : "property list int int vertex_indices\n";
        s += "end_header\n";
        auto putFloat = [&](float v) {
            if (binary) s.append(reinterpret_cast<const char*>(&v), 4);
            else s += std::to_string(v) + " ";
        };
        auto putInt = [&](int32_t v, bool asByte) {
            if (!binary) s += std::to_string(v) + " ";
            else if (asByte) s += char(uint8_t(v));
            else s.append(reinterpret_cast<const char*>(&v), 4);
        };
        static_assert(std::endian::native == std::endian::little, "binary test files are written little-endian");
        for (int r = 0; r <= rows; ++r)
            for (int c = 0; c <= columns; ++c) {
                putFloat(float(c) / float(columns));
                putFloat(float(r) / float(rows));
                putFloat(height(r, c));
                if (!binary) s += "\n";
            }
        for (const std::vector<int>& list : lists) {
            putInt(int32_t(list.size()), faceList);
            for (int v : list) putInt(v, false);
            if (!binary) s += "\n";
        }
        return s;
    }
};

}  // namespace cuberille::testing
