#include "voxel/face_expansion.h"

#include "voxel/packing.h"

namespace cuberille::voxel {
namespace {

/// The four corners of the face on `axis` at the high (positive) or low side, counter-clockwise
/// seen from outside the voxel.
void faceCorners(const glm::dvec3& lo, const glm::dvec3& hi, int axis, bool positive, glm::dvec3 (&c)[4]) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    const double w = positive ? hi[axis] : lo[axis];
    auto corner = [&](double a, double b) {
        glm::dvec3 p;
        p[axis] = w;
        p[u] = a;
        p[v] = b;
        return p;
    };
    if (positive) {
        c[0] = corner(lo[u], lo[v]), c[1] = corner(hi[u], lo[v]), c[2] = corner(hi[u], hi[v]), c[3] = corner(lo[u], hi[v]);
    } else {
        c[0] = corner(lo[u], lo[v]), c[1] = corner(lo[u], hi[v]), c[2] = corner(hi[u], hi[v]), c[3] = corner(hi[u], lo[v]);
    }
}

/// The faces of a voxel on the sides of a region: the skirt of a stand-in.
uint8_t regionSideFaces(const glm::uvec3& p, const VoxelRegion& r) {
    uint8_t faces = 0;
    for (int axis = 0; axis < 3; ++axis) {
        if (p[axis] + 1 == r.hi[axis]) faces |= uint8_t(1u << (2 * axis));
        if (p[axis] == r.lo[axis]) faces |= uint8_t(2u << (2 * axis));
    }
    return faces;
}

}  // namespace

void expandVoxelFaces(const VoxelModel& model, const BlockVoxels& block, const glm::dvec3& camera, FaceMesh& out,
                      const glm::vec3* overrideColor, const VoxelRegion* region) {
    const VoxelBoxes boxes(model, block.level, block.coord);
    for (size_t i = 0; i < block.voxels.size(); ++i) {
        const uint32_t packed = block.voxels[i];
        const glm::uvec3 position = voxelPositionInBlock(packed);
        uint8_t mask = voxelFaceMask(packed);
        if (region) {
            if (glm::any(glm::lessThan(position, region->lo)) || glm::any(glm::greaterThanEqual(position, region->hi)))
                continue;
            mask |= regionSideFaces(position, *region);
        }
        const glm::dvec3 lo = boxes.lowCorner(position);
        const glm::dvec3 hi = lo + boxes.voxelSize;
        // Active faces the camera is in front of: at most one per axis.
        uint8_t facing = 0;
        if (camera.x > hi.x) facing |= kFacePosX;
        if (camera.x < lo.x) facing |= kFaceNegX;
        if (camera.y > hi.y) facing |= kFacePosY;
        if (camera.y < lo.y) facing |= kFaceNegY;
        if (camera.z > hi.z) facing |= kFacePosZ;
        if (camera.z < lo.z) facing |= kFaceNegZ;
        const uint8_t emit = mask & facing;
        if (!emit) continue;
        ++out.voxels;
        const glm::vec3 normal = unpackNormal1010102(block.normals[i]);
        const glm::vec3 color = overrideColor ? *overrideColor : unpackSrgba8Rgb(block.colors[i]);
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                if (!(emit & (1u << (2 * axis + side)))) continue;
                glm::dvec3 c[4];
                faceCorners(lo, hi, axis, side == 0, c);
                const uint32_t base = uint32_t(out.positions.size());
                for (const glm::dvec3& p : c) {
                    out.positions.push_back(glm::vec3(p));
                    out.normals.push_back(normal);
                    out.colors.push_back(color);
                }
                out.indices.insert(out.indices.end(), {base, base + 1, base + 2, base, base + 2, base + 3});
                ++out.faces;
            }
    }
}

}  // namespace cuberille::voxel
