#pragma once
// Which structure answers the shadow stage's rays (shadows and ambient occlusion) about the
// casters: the two seeds' answers to animation, side by side on the same frames.
//
// - Bvh (`--accel bvh`, the default): a hierarchy built once and made to follow each new pose by
//   refitting, Larsson's lazy refit, or rebuilding (`--bvh-update`; rt/deforming_bvh.h, after
//   Lauterbach et al.), queried through the eight-wide tree.
// - Grid (`--accel grid`): a uniform grid rebuilt from scratch for every pose, so any motion costs
//   the same linear build (Wald et al. 2006, rt/uniform_grid.h): single rays walk it by the
//   3D-DDA.
//
// The shadow stage sends rays that travel together as packets through either (rt/shadows.cpp):
// the grid's slice by slice, the wide BVH's node by node (rt/wide_bvh.h).
//
// Both answer exactly as brute force over every caster does (the same watertight test and hit
// definition, rt/ray.h), so the masks, and the images, are the same bits whichever answers.

#include <cstdint>

#include "rt/deforming_bvh.h"
#include "rt/uniform_grid.h"

namespace cuberille::rt {

enum class CasterAccel : uint8_t { Bvh, Grid };

/// The any-hit query of the stage's rays: the grid's when there is one, else the BVH's.
struct CasterRays {
    const DeformingBvh* bvh = nullptr;
    const UniformGrid* grid = nullptr;
    TriangleMeshView mesh = {};  // the grid's triangles (the BVH keeps its own)
    /// Alpha-tested casters (rt/caster_alpha_test.h): a hit counts only where the material's
    /// alpha passes its cutoff. Null: every caster is opaque.
    const HitFilter* filter = nullptr;

    bool anyHit(const Ray& ray) const { return grid ? rt::anyHit(*grid, mesh, ray, nullptr, filter) : bvh->anyHit(ray, filter); }
    /// Rays that travel together (a tile's receivers toward one light, one receiver's rays toward
    /// a light's disk) as packets: the grid's frustum packets or the wide BVH's. Each answer is
    /// its ray's anyHit.
    void anyHits(std::span<const Ray> rays, std::span<uint8_t> occluded) const {
        if (grid) rt::anyHits(*grid, mesh, rays, occluded, nullptr, filter);
        else bvh->anyHits(rays, occluded, filter);
    }
};

}  // namespace cuberille::rt
