#pragma once
// Meshes made in code for the voxel tests, in grid units: a test voxelizes into the grid
// {R, origin 0, extent R}, so a model coordinate is a grid coordinate and lattice points (multiples
// of 1/1024 of a voxel) are exact in float, in the unit cube and in the brute-force reference.

#include <array>
#include <cmath>
#include <random>
#include <set>
#include <tuple>
#include <vector>

#include <glm/glm.hpp>

#include "scene/mesh.h"
#include "voxel/mesh_view.h"
#include "voxel/octree_voxelizer.h"

namespace cuberille::testing {

using Triangle = std::array<glm::vec3, 3>;
using VoxelKey = std::tuple<uint32_t, uint32_t, uint32_t>;

constexpr double kLatticeSteps = 1024.0;  // lattice points per voxel

inline scene::Mesh meshOf(const std::vector<Triangle>& tris, const std::vector<glm::vec3>& colors = {}) {
    scene::Mesh m;
    for (size_t t = 0; t < tris.size(); ++t)
        for (int k = 0; k < 3; ++k) {
            m.indices.push_back(uint32_t(m.positions.size()));
            m.positions.push_back(tris[t][k]);
            if (!colors.empty()) m.colors.push_back(colors[t]);
        }
    m.color = glm::vec3(1.0f);
    scene::computeVertexNormals(m);
    return m;
}

inline std::unique_ptr<voxel::MeshView> viewOf(const std::vector<Triangle>& tris, uint32_t chunkTriangles = 7,
                                               const std::vector<glm::vec3>& colors = {}) {
    std::vector<scene::Mesh> meshes;
    meshes.push_back(meshOf(tris, colors));
    return voxel::viewOfMeshes(std::move(meshes), "test mesh", !colors.empty(), chunkTriangles);
}

inline voxel::VoxelModel voxelizeInGrid(const voxel::MeshView& view, uint32_t resolution, voxel::Separability s) {
    voxel::VoxelizeOptions o;
    o.resolution = resolution;
    o.separability = s;
    o.grid = voxel::VoxelGrid{resolution, glm::dvec3(0.0), double(resolution)};
    return voxel::voxelizeMesh(view, o);
}

inline std::set<VoxelKey> voxelSet(const voxel::VoxelModel& m) {
    std::set<VoxelKey> s;
    for (const voxel::VoxelBlock& b : m.blocks)
        for (size_t v = 0; v < b.voxels.size(); ++v) {
            const glm::uvec3 p = m.gridPosition(b, v);
            s.insert({p.x, p.y, p.z});
        }
    return s;
}

inline float onLattice(double x) { return float(std::round(x * kLatticeSteps) / kLatticeSteps); }

/// Unit-sphere points subdivided from an icosahedron: a closed, consistently wound mesh.
inline std::vector<Triangle> icosphere(int subdivisions, const glm::dvec3& centre, double radius, const glm::dmat3& rotation) {
    const double t = (1.0 + std::sqrt(5.0)) / 2.0;
    std::vector<glm::dvec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    std::vector<std::array<glm::dvec3, 3>> f;
    const int idx[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                            {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                            {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
    for (auto& i : idx) f.push_back({glm::normalize(v[i[0]]), glm::normalize(v[i[1]]), glm::normalize(v[i[2]])});
    for (int s = 0; s < subdivisions; ++s) {
        std::vector<std::array<glm::dvec3, 3>> g;
        for (auto& tri : f) {
            const glm::dvec3 a = glm::normalize(tri[0] + tri[1]), b = glm::normalize(tri[1] + tri[2]),
                             c = glm::normalize(tri[2] + tri[0]);
            g.push_back({tri[0], a, c});
            g.push_back({tri[1], b, a});
            g.push_back({tri[2], c, b});
            g.push_back({a, b, c});
        }
        f = std::move(g);
    }
    std::vector<Triangle> out;
    for (auto& tri : f) {
        Triangle r;
        for (int k = 0; k < 3; ++k) r[k] = glm::vec3(centre + radius * (rotation * tri[k]));
        out.push_back(r);
    }
    return out;
}

inline glm::dmat3 randomRotation(std::mt19937& rng) {
    std::uniform_real_distribution<double> u(0.0, 2.0 * 3.14159265358979);
    const double a = u(rng), b = u(rng), c = u(rng);
    const glm::dmat3 rx(1, 0, 0, 0, std::cos(a), std::sin(a), 0, -std::sin(a), std::cos(a));
    const glm::dmat3 ry(std::cos(b), 0, -std::sin(b), 0, 1, 0, std::sin(b), 0, std::cos(b));
    const glm::dmat3 rz(std::cos(c), std::sin(c), 0, -std::sin(c), std::cos(c), 0, 0, 0, 1);
    return rz * ry * rx;
}

}  // namespace cuberille::testing
