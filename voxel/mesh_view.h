#pragma once
// Mesh views (Chajdas 2015, section 3.1.1): one interface over every geometry source the
// voxelizer reads, so the rasterizer never knows whether triangles came from a geometry stream
// (.cgs), a PLY scan, an OBJ or a glTF file. A view is a sequence of independent chunks; each can
// be described without being read (its triangle count and bounds), which is what lets the
// voxelizer size its grid before loading any triangles and hand chunks to threads one at a time.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <glm/glm.hpp>

#include "scene/input_error.h"
#include "scene/mesh.h"

namespace cuberille::voxel {

/// One self-contained piece of a mesh: its own vertices, and three indices per triangle into
/// them. Normals are always present (computed from the whole mesh when its file had none, so
/// chunk borders do not show); colours are linear RGB, present when the source has any colour.
struct GeometryChunk {
    std::vector<glm::vec3> positions;
    std::vector<glm::vec3> normals;
    std::vector<glm::vec3> colors;  // empty, or one per position
    std::vector<uint32_t> indices;

    size_t triangleCount() const { return indices.size() / 3; }
    bool hasColors() const { return !colors.empty(); }
};

/// What is known about a chunk without reading it.
struct ChunkInfo {
    uint32_t vertexCount = 0;
    uint32_t triangleCount = 0;
    bool hasColors = false;
    glm::vec3 boundsMin{0.0f}, boundsMax{0.0f};
};

class MeshView {
public:
    virtual ~MeshView() = default;
    virtual size_t chunkCount() const = 0;
    virtual const ChunkInfo& chunkInfo(size_t chunk) const = 0;
    /// Thread-safe: the voxelizer's threads read different chunks at once. Throws
    /// scene::InputError naming the file and chunk for bad data.
    virtual GeometryChunk readChunk(size_t chunk) const = 0;
    /// For messages: the file (or a description) the view reads.
    virtual const std::string& sourceName() const = 0;

    // Derived from the chunk infos.
    uint64_t triangleCount() const;
    bool hasColors() const;  // any chunk has colours
    /// The union of the chunk bounds; min > max when there are no vertices.
    void bounds(glm::vec3& min, glm::vec3& max) const;
};

/// Triangles per chunk when a view splits a mesh held in memory, and when `cuberille pack`
/// writes a geometry stream: large enough that the per-chunk overhead vanishes, small enough
/// that threads balance on a model of a few chunks.
constexpr uint32_t kDefaultChunkTriangles = 1u << 14;

/// Meshes already in memory, cut into chunks of at most chunkTriangles triangles, each with its
/// own compact vertex array. Colours (the material colour times vertex colours) are kept when
/// keepColors is set.
std::unique_ptr<MeshView> viewOfMeshes(std::vector<scene::Mesh> meshes, std::string sourceName,
                                       bool keepColors, uint32_t chunkTriangles = kDefaultChunkTriangles);

/// Any geometry file: a geometry stream (.cgs) is opened in place (chunks read on demand);
/// .ply, .ply.gz, .obj, .gltf and .glb (static pose: no animation applied beyond the file's
/// node transforms at time 0) are loaded through scene/ and cut into chunks of chunkTriangles.
/// Colours come along when the file has vertex colours or materials (OBJ, glTF). Throws
/// scene::InputError.
std::unique_ptr<MeshView> openMeshView(const std::filesystem::path& path, const scene::WarningSink& warn,
                                       uint32_t chunkTriangles = kDefaultChunkTriangles);

bool isGeometryStreamFile(const std::filesystem::path& path);

}  // namespace cuberille::voxel
