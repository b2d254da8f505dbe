#pragma once
// Top-down BVH construction over triangles (Lauterbach chapter 5; Wald's binned SAH).
//
// Both builds split a node's primitives by their centroids, in place, and recurse; the two halves
// of a large node build in parallel. The tree is a pure function of the mesh and the options:
// partitions are deterministic, parallel reductions combine fixed chunks in a fixed order, and
// nodes are laid out depth-first after the build, so thread count and scheduling change nothing.

#include <cstdint>

#include "rt/bvh.h"
#include "rt/triangle_mesh.h"

namespace cuberille::rt {

struct BvhBuildOptions {
    BvhBuildMethod method = BvhBuildMethod::BinnedSah;
    int sahBins = 16;                      // centroid bins per axis
    float traversalCost = 1.0f;            // cost of visiting a node, in triangle tests
    uint32_t maxLeafPrimitives = 8;        // SAH: a node with more is always split
    uint32_t medianLeafPrimitives = 4;     // spatial median: a node with at most this is a leaf
};

Bvh buildBvh(const TriangleMeshView& mesh, const BvhBuildOptions& options = {});

/// The root box a hierarchy over these triangles must have: a slow-but-sure check for tests.
Aabb meshBounds(const TriangleMeshView& mesh);

}  // namespace cuberille::rt
