#include "voxel/voxel_export.h"

#include <charconv>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "scene/input_error.h"

namespace cuberille::voxel {

void writeVoxelExport(const VoxelModel& model, std::ostream& out) {
    writeVoxelExportHeader(model.grid, out);
    std::string text;
    for (const VoxelBlock& b : model.blocks) {
        if (b.level != 0) continue;
        appendVoxelExportLines(b, model.blockSize, text);
        if (text.size() > (1u << 20)) {
            out << text;
            text.clear();
        }
    }
    out << text;
}

void writeVoxelExportHeader(const VoxelGrid& grid, std::ostream& out) {
    char line[256];
    std::snprintf(line, sizeof line, "# cuberille voxels %u %.17g %.17g %.17g %.17g\n", grid.resolution, grid.origin.x,
                  grid.origin.y, grid.origin.z, grid.extent);
    out << line;
}

void appendVoxelExportLines(const VoxelBlock& b, uint32_t blockSize, std::string& text) {
    char line[64];
    for (uint32_t packed : b.voxels) {
        const glm::uvec3 p = b.coord * blockSize + voxelPositionInBlock(packed);
        const int n = std::snprintf(line, sizeof line, "%u %u %u\n", p.x, p.y, p.z);
        text.append(line, size_t(n));
    }
}

VoxelExport readVoxelExport(const std::filesystem::path& path) {
    std::ifstream in(path);
    if (!in) throw scene::InputError(path.string() + ": cannot open");
    VoxelExport e;
    std::string line;
    size_t lineNumber = 0;
    auto fail = [&](const std::string& problem) {
        throw scene::InputError(path.string() + ":" + std::to_string(lineNumber) + ": " + problem);
    };
    while (std::getline(in, line)) {
        ++lineNumber;
        std::istringstream s(line);
        if (lineNumber == 1) {
            std::string hash, tool, kind;
            s >> hash >> tool >> kind >> e.grid.resolution >> e.grid.origin.x >> e.grid.origin.y >> e.grid.origin.z >>
                e.grid.extent;
            if (!s || hash != "#" || tool != "cuberille" || kind != "voxels")
                fail("expected '# cuberille voxels R ox oy oz extent'");
            continue;
        }
        glm::uvec3 p;
        s >> p.x >> p.y >> p.z;
        if (!s) fail("expected 'i j k'");
        if (p.x >= e.grid.resolution || p.y >= e.grid.resolution || p.z >= e.grid.resolution)
            fail("voxel outside the grid");
        e.voxels.push_back(p);
    }
    if (lineNumber == 0) fail("empty file");
    return e;
}

}  // namespace cuberille::voxel
