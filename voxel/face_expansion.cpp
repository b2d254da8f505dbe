#include "voxel/face_expansion.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

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

/// Faces whose screen box is wider or taller than this many pixels are kept without looking for
/// their samples: they cover some in all but rare slivers, and the search would cost more than
/// drawing them.
constexpr double kSearchedFacePixels = 2.0;

/// The pixels [first, last] whose sample at `offset` (pixels from the pixel's corner) lies in
/// [lo, hi] on one axis; empty when first > last.
inline void samplePixels(double lo, double hi, double offset, int pixels, int& first, int& last) {
    // Clamped to the viewport first, so the conversions stay in range; ceil and floor by
    // truncation and one correction (baseline x86-64 has no rounding instruction: std::ceil is a
    // library call there).
    const double from = std::clamp(lo - offset, -1.0, double(pixels)), to = std::clamp(hi - offset, -1.0, double(pixels));
    first = int(from), last = int(to);
    first += double(first) < from;
    last -= double(last) > to;
    first = std::max(first, 0), last = std::min(last, pixels - 1);
}

/// Whether a sample of some pixel lies in the box.
bool boxHoldsSample(const glm::dvec2& lo, const glm::dvec2& hi, const SampleFootprint& f) {
    for (const glm::dvec2& s : f.samples) {
        int x0, x1, y0, y1;
        samplePixels(lo.x, hi.x, s.x, f.widthPixels, x0, x1);
        samplePixels(lo.y, hi.y, s.y, f.heightPixels, y0, y1);
        if (x0 <= x1 && y0 <= y1) return true;
    }
    return false;
}

/// Whether a sample of some pixel lies in the convex quad (window pixels, either winding) widened
/// by kFootprintMarginPixels: each edge's line moved outwards by at least the margin (by margin
/// times |dx| + |dy| over the edge's length, which is at least 1: no square root). `lo`, `hi`:
/// the widened quad's box.
bool quadHoldsSample(const glm::dvec2 (&q)[4], const glm::dvec2& lo, const glm::dvec2& hi, const SampleFootprint& f) {
    double area2 = 0.0;
    for (int i = 0; i < 4; ++i) area2 += q[i].x * q[(i + 1) % 4].y - q[(i + 1) % 4].x * q[i].y;
    const double orientation = area2 >= 0.0 ? 1.0 : -1.0;
    double edgeA[4], edgeB[4], edgeC[4];  // inside: a x + b y + c >= 0
    for (int i = 0; i < 4; ++i) {
        const glm::dvec2 d = q[(i + 1) % 4] - q[i];
        edgeA[i] = -d.y * orientation, edgeB[i] = d.x * orientation;
        edgeC[i] = -(edgeA[i] * q[i].x + edgeB[i] * q[i].y) + kFootprintMarginPixels * (std::abs(d.x) + std::abs(d.y));
    }
    for (const glm::dvec2& s : f.samples) {
        int x0, x1, y0, y1;
        samplePixels(lo.x, hi.x, s.x, f.widthPixels, x0, x1);
        samplePixels(lo.y, hi.y, s.y, f.heightPixels, y0, y1);
        for (int y = y0; y <= y1; ++y)
            for (int x = x0; x <= x1; ++x) {
                const double sx = x + s.x, sy = y + s.y;
                bool inside = true;
                for (int i = 0; i < 4 && inside; ++i) inside = edgeA[i] * sx + edgeB[i] * sy + edgeC[i] >= 0.0;
                if (inside) return true;
            }
    }
    return false;
}

/// A block's faces against a footprint: the clip position of a voxel corner is affine in its
/// grid position, so a voxel's eight corners cost one matrix product and seven additions.
class FaceFootprints {
public:
    FaceFootprints(const SampleFootprint& f, const VoxelBoxes& boxes) : f_(f) {
        origin_ = f.clipFromModel * glm::dvec4(boxes.blockOrigin, 1.0);
        for (int axis = 0; axis < 3; ++axis) step_[axis] = f.clipFromModel[axis] * boxes.voxelSize;
        halfWidth_ = 0.5 * f.widthPixels, halfHeight_ = 0.5 * f.heightPixels;
        // How far a corner's clip x, y and w lie from the centre's, at most (the same for every voxel).
        halfExtent_ = 0.5 * (glm::abs(step_[0]) + glm::abs(step_[1]) + glm::abs(step_[2]));
    }

    /// False when no sample can lie under the voxel: a box about the projected centre that holds
    /// every corner (a corner at c + d in clip space lies at x/w with |x/w - cx/cw| at most
    /// (|dx| + |cx/cw| |dw|) / (cw - |dw|)), for two divisions instead of eight.
    bool mayCoverAnySample(const glm::uvec3& p) const {
        const glm::dvec4 centre =
            origin_ + step_[0] * (p.x + 0.5) + step_[1] * (p.y + 0.5) + step_[2] * (p.z + 0.5);
        const double nearestW = centre.w - halfExtent_.w;
        if (!(nearestW > 0.0) || centre.z - halfExtent_.z < 0.0) return true;  // may cross the near plane
        const double invW = 1.0 / centre.w, x = centre.x * invW, y = centre.y * invW;
        const double invNearestW = 1.0 / nearestW;
        const double rx = (halfExtent_.x + std::abs(x) * halfExtent_.w) * invNearestW * halfWidth_ + kFootprintMarginPixels;
        const double ry = (halfExtent_.y + std::abs(y) * halfExtent_.w) * invNearestW * halfHeight_ + kFootprintMarginPixels;
        const glm::dvec2 at((x + 1.0) * halfWidth_, (1.0 - y) * halfHeight_);
        return boxHoldsSample(at - glm::dvec2(rx, ry), at + glm::dvec2(rx, ry), f_);
    }

    /// The faces of `faces` (of the voxel at `p` in the block) that may cover a sample: none when
    /// the voxel's whole box holds no sample, else each face by its own quad.
    uint8_t mayCoverSamples(const glm::uvec3& p, uint8_t faces) const {
        if (!mayCoverAnySample(p)) return 0;
        glm::dvec2 window[8];  // corner k at p + (k & 1, k >> 1 & 1, k >> 2 & 1)
        const glm::dvec4 base = origin_ + step_[0] * double(p.x) + step_[1] * double(p.y) + step_[2] * double(p.z);
        glm::dvec2 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
        for (int k = 0; k < 8; ++k) {
            glm::dvec4 clip = base;
            if (k & 1) clip += step_[0];
            if (k & 2) clip += step_[1];
            if (k & 4) clip += step_[2];
            if (!(clip.w > 0.0) || clip.z < 0.0) return faces;  // crosses the near plane: clipped by the rasterizer; kept whole
            const double invW = 1.0 / clip.w;
            window[k] = {(clip.x * invW + 1.0) * halfWidth_, (1.0 - clip.y * invW) * halfHeight_};
            lo = glm::min(lo, window[k]), hi = glm::max(hi, window[k]);
        }
        if (!boxHoldsSample(lo - kFootprintMarginPixels, hi + kFootprintMarginPixels, f_)) return 0;
        // The corners of the face on `axis`, in order around it, as bits along the other two axes.
        static constexpr int kAround[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        uint8_t kept = 0;
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                const uint8_t bit = uint8_t(1u << (2 * axis + side));
                if (!(faces & bit)) continue;
                const int u = (axis + 1) % 3, v = (axis + 2) % 3;
                glm::dvec2 quad[4];
                for (int c = 0; c < 4; ++c)
                    quad[c] = window[(side == 0 ? 1 << axis : 0) | kAround[c][0] << u | kAround[c][1] << v];
                glm::dvec2 faceLo = glm::min(glm::min(quad[0], quad[1]), glm::min(quad[2], quad[3]));
                glm::dvec2 faceHi = glm::max(glm::max(quad[0], quad[1]), glm::max(quad[2], quad[3]));
                if (faceHi.x - faceLo.x > kSearchedFacePixels || faceHi.y - faceLo.y > kSearchedFacePixels ||
                    quadHoldsSample(quad, faceLo - kFootprintMarginPixels, faceHi + kFootprintMarginPixels, f_))
                    kept |= bit;
            }
        return kept;
    }

private:
    const SampleFootprint& f_;
    glm::dvec4 origin_, step_[3];
    double halfWidth_ = 0.0, halfHeight_ = 0.0;
    glm::dvec4 halfExtent_{0.0};
};

}  // namespace

void expandVoxelFaces(const VoxelModel& model, const BlockVoxels& block, const glm::dvec3& camera, FaceMesh& out,
                      const glm::vec3* overrideColor, const VoxelRegion* region, const SampleFootprint* footprint) {
    const VoxelBoxes boxes(model, block.level, block.coord);
    std::optional<FaceFootprints> footprints;
    if (footprint) footprints.emplace(*footprint, boxes);
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
        uint8_t emit = mask & facing;
        if (emit && footprints) {
            const uint8_t covering = footprints->mayCoverSamples(position, emit);
            out.facesBetweenSamples += uint64_t(__builtin_popcount(emit ^ covering));
            emit = covering;
        }
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
