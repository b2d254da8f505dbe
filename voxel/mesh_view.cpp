#include "voxel/mesh_view.h"

#include <algorithm>
#include <limits>
#include <unordered_map>

#include "scene/file_names.h"
#include "scene/gltf_loader.h"
#include "scene/obj_loader.h"
#include "scene/ply_loader.h"
#include "voxel/geometry_stream.h"

namespace cuberille::voxel {
namespace {

/// A range of one mesh's triangles.
struct ChunkRange {
    uint32_t mesh = 0;
    size_t firstTriangle = 0, triangleCount = 0;
};

class MeshesView final : public MeshView {
public:
    MeshesView(std::vector<scene::Mesh> meshes, std::string name, bool keepColors, uint32_t chunkTriangles)
        : meshes_(std::move(meshes)), name_(std::move(name)), keepColors_(keepColors) {
        chunkTriangles = std::max<uint32_t>(chunkTriangles, 1);
        for (uint32_t m = 0; m < meshes_.size(); ++m) {
            const size_t n = meshes_[m].triangleCount();
            for (size_t first = 0; first < n; first += chunkTriangles) {
                ranges_.push_back({m, first, std::min<size_t>(chunkTriangles, n - first)});
                infos_.push_back(describe(ranges_.back()));
            }
        }
    }

    size_t chunkCount() const override { return ranges_.size(); }
    const ChunkInfo& chunkInfo(size_t chunk) const override { return infos_[chunk]; }
    const std::string& sourceName() const override { return name_; }

    GeometryChunk readChunk(size_t chunk) const override {
        const ChunkRange& r = ranges_[chunk];
        const scene::Mesh& mesh = meshes_[r.mesh];
        GeometryChunk c;
        // Vertices renumbered in order of first use, so the chunk is self-contained.
        std::unordered_map<uint32_t, uint32_t> local;
        c.indices.reserve(r.triangleCount * 3);
        for (size_t i = r.firstTriangle * 3; i < (r.firstTriangle + r.triangleCount) * 3; ++i) {
            const uint32_t v = mesh.indices[i];
            auto [it, inserted] = local.try_emplace(v, uint32_t(c.positions.size()));
            if (inserted) {
                c.positions.push_back(mesh.positions[v]);
                c.normals.push_back(mesh.normals[v]);
                if (keepColors_) c.colors.push_back(mesh.colors.empty() ? mesh.color : mesh.color * mesh.colors[v]);
            }
            c.indices.push_back(it->second);
        }
        return c;
    }

private:
    ChunkInfo describe(const ChunkRange& r) const {
        const scene::Mesh& mesh = meshes_[r.mesh];
        ChunkInfo info;
        info.triangleCount = uint32_t(r.triangleCount);
        info.hasColors = keepColors_;
        glm::vec3 lo(std::numeric_limits<float>::max()), hi(std::numeric_limits<float>::lowest());
        std::vector<uint32_t> seen;
        for (size_t i = r.firstTriangle * 3; i < (r.firstTriangle + r.triangleCount) * 3; ++i) {
            const glm::vec3& p = mesh.positions[mesh.indices[i]];
            lo = glm::min(lo, p);
            hi = glm::max(hi, p);
            seen.push_back(mesh.indices[i]);
        }
        std::sort(seen.begin(), seen.end());
        info.vertexCount = uint32_t(std::unique(seen.begin(), seen.end()) - seen.begin());
        info.boundsMin = lo;
        info.boundsMax = hi;
        return info;
    }

    std::vector<scene::Mesh> meshes_;
    std::string name_;
    bool keepColors_;
    std::vector<ChunkRange> ranges_;
    std::vector<ChunkInfo> infos_;
};

}  // namespace

uint64_t MeshView::triangleCount() const {
    uint64_t n = 0;
    for (size_t i = 0; i < chunkCount(); ++i) n += chunkInfo(i).triangleCount;
    return n;
}

bool MeshView::hasColors() const {
    for (size_t i = 0; i < chunkCount(); ++i)
        if (chunkInfo(i).hasColors) return true;
    return false;
}

void MeshView::bounds(glm::vec3& min, glm::vec3& max) const {
    min = glm::vec3(std::numeric_limits<float>::max());
    max = glm::vec3(std::numeric_limits<float>::lowest());
    for (size_t i = 0; i < chunkCount(); ++i) {
        if (chunkInfo(i).triangleCount == 0) continue;
        min = glm::min(min, chunkInfo(i).boundsMin);
        max = glm::max(max, chunkInfo(i).boundsMax);
    }
}

std::unique_ptr<MeshView> viewOfMeshes(std::vector<scene::Mesh> meshes, std::string sourceName, bool keepColors,
                                       uint32_t chunkTriangles) {
    return std::make_unique<MeshesView>(std::move(meshes), std::move(sourceName), keepColors, chunkTriangles);
}

bool isGeometryStreamFile(const std::filesystem::path& path) {
    return scene::fileKindOf(path) == scene::FileKind::GeometryStream;
}

std::unique_ptr<MeshView> openMeshView(const std::filesystem::path& path, const scene::WarningSink& warn,
                                       uint32_t chunkTriangles) {
    if (isGeometryStreamFile(path)) return openGeometryStream(path);
    const scene::FileKind kind = scene::fileKindOf(path);
    if (kind == scene::FileKind::Obj) return viewOfMeshes(scene::loadObj(path, warn), path.string(), true, chunkTriangles);
    if (scene::isGltfKind(kind))
        return viewOfMeshes(scene::loadGltf(path, warn, 0.0f).meshes, path.string(), true, chunkTriangles);
    if (kind == scene::FileKind::Ply) {
        scene::Mesh m = scene::loadPly(path);
        const bool colored = !m.colors.empty();
        if (colored) m.color = glm::vec3(1.0f);  // a scan's colours are its own, not tinted
        std::vector<scene::Mesh> meshes;
        meshes.push_back(std::move(m));
        return viewOfMeshes(std::move(meshes), path.string(), colored, chunkTriangles);
    }
    throw scene::InputError(path.string() + ": not a mesh: expected .cgs, .ply, .ply.gz, .obj, .gltf or .glb");
}

}  // namespace cuberille::voxel
