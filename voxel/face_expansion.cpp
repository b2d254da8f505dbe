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
    FaceFootprints(const SampleFootprint& f, const VoxelBoxes& boxes, uint32_t blockSize, const DepthFootprint* depth)
        : f_(f), depth_(depth) {
        origin_ = f.clipFromModel * glm::dvec4(boxes.blockOrigin, 1.0);
        if (depth) {
            // What the rasterizer's float transform of a corner can be off by, over the whole
            // block (hiddenDepthMargin): 2^-20 of the sums of |matrix entry x coordinate| of the
            // clip z and w rows, at the block's largest coordinates.
            const glm::dvec3 far = boxes.blockOrigin + double(blockSize) * boxes.voxelSize;
            const glm::dvec3 magnitude = glm::max(glm::abs(boxes.blockOrigin), glm::abs(far));
            const glm::dmat4& m = f.clipFromModel;
            clipZError_ = std::abs(m[3][2]), clipWError_ = std::abs(m[3][3]);
            for (int j = 0; j < 3; ++j)
                clipZError_ += std::abs(m[j][2]) * magnitude[j], clipWError_ += std::abs(m[j][3]) * magnitude[j];
            clipZError_ *= kTransformRounding, clipWError_ *= kTransformRounding;
        }
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
    /// the voxel's whole box holds no sample or lies behind the depth footprint (then `behind`),
    /// else each face by its own quad.
    uint8_t mayCoverSamples(const glm::uvec3& p, uint8_t faces, bool& behind) const {
        behind = false;
        if (!mayCoverAnySample(p)) return 0;
        glm::dvec2 window[8];  // corner k at p + (k & 1, k >> 1 & 1, k >> 2 & 1)
        const glm::dvec4 base = origin_ + step_[0] * double(p.x) + step_[1] * double(p.y) + step_[2] * double(p.z);
        glm::dvec2 lo(std::numeric_limits<double>::infinity()), hi(-std::numeric_limits<double>::infinity());
        double nearestZ = std::numeric_limits<double>::infinity(), farthestZ = -nearestZ, nearestW = nearestZ;
        for (int k = 0; k < 8; ++k) {
            glm::dvec4 clip = base;
            if (k & 1) clip += step_[0];
            if (k & 2) clip += step_[1];
            if (k & 4) clip += step_[2];
            if (!(clip.w > 0.0) || clip.z < 0.0) return faces;  // crosses the near plane: clipped by the rasterizer; kept whole
            const double invW = 1.0 / clip.w;
            window[k] = {(clip.x * invW + 1.0) * halfWidth_, (1.0 - clip.y * invW) * halfHeight_};
            lo = glm::min(lo, window[k]), hi = glm::max(hi, window[k]);
            const double z = clip.z * invW;
            nearestZ = std::min(nearestZ, z), farthestZ = std::max(farthestZ, z), nearestW = std::min(nearestW, clip.w);
        }
        if (!boxHoldsSample(lo - kFootprintMarginPixels, hi + kFootprintMarginPixels, f_)) return 0;
        if (depth_ && behindDepth(lo, hi, nearestZ, farthestZ, nearestW)) {
            behind = true;
            return 0;
        }
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
    /// Whether no sample the voxel's faces cover can pass a LESS test against the depth
    /// footprint: the nearest key any of them can get, less hiddenDepthMargin, is not below the
    /// farthest key stored in any 8x8 block under the voxel's widened box. `lo`, `hi`: the box in
    /// window pixels; nearestZ, farthestZ: the corners' window depths; nearestW: their least clip w.
    bool behindDepth(const glm::dvec2& lo, const glm::dvec2& hi, double nearestZ, double farthestZ,
                     double nearestW) const {
        const DepthFootprint& d = *depth_;
        if (hi.x - lo.x > kDepthTestedVoxelPixels || hi.y - lo.y > kDepthTestedVoxelPixels) return false;
        const double margin = hiddenDepthMargin(nearestZ, farthestZ, nearestW);
        // The depth key is the window depth clamped to [0, 1], signed (raster/depth.h): monotonic
        // in the depth, so the nearest key is that of the nearest depth (or, reversed, the farthest).
        auto key = [&](double z) { return double(d.keySign) * std::clamp(z, 0.0, 1.0); };
        const double nearestKey = std::min(key(nearestZ), key(farthestZ)) - margin;
        // Pixels by truncation: the box lies within a few pixels of the image here (it holds a
        // sample, and is at most kDepthTestedVoxelPixels wide), and a pixel one too far left or up
        // (truncation of a negative value) only adds a block to the test.
        const int x0 = std::max(0, int(lo.x - kFootprintMarginPixels) / d.blockSizePixels);
        const int y0 = std::max(0, int(lo.y - kFootprintMarginPixels) / d.blockSizePixels);
        const int x1 = std::min(d.blocksX - 1, int(hi.x + kFootprintMarginPixels) / d.blockSizePixels);
        const int y1 = std::min(d.blocksY - 1, int(hi.y + kFootprintMarginPixels) / d.blockSizePixels);
        if (x0 > x1 || y0 > y1) return false;
        for (int by = y0; by <= y1; ++by)
            for (int bx = x0; bx <= x1; ++bx)
                if (!(double(d.farthestKey[size_t(by) * size_t(d.blocksX) + size_t(bx)]) <= nearestKey)) return false;
        return true;
    }

    /// How far in front of nearestZ the rasterizer's depth at a sample one of the voxel's faces
    /// covers can lie, in window depth. Three sources, each bounded with room to spare:
    /// - Each face corner's float window depth against the exact z / w found here: the position
    ///   rounded to float, the float matrix product (four products, three sums) and the division
    ///   are seven or eight roundings of 2^-24 relative to the terms' magnitudes; 2^-20 of them
    ///   (sixteen roundings, kTransformRounding) bounds the error of clip z and w, so of z / w at
    ///   most (Ez + |z / w| Ew) / w, with E = 2^-20 the sum of |matrix entry x coordinate| of that
    ///   row (clipZError_, clipWError_: over the block's largest coordinates).
    /// - Exactly evaluated, the depth plane at a covered sample is a convex combination of its
    ///   triangle's three vertex depths (the sample lies in the snapped triangle the plane was fit
    ///   to), so not in front of the nearest corner.
    /// - The plane is stored and evaluated in float: z0 + gx X + gy Y, X and Y within the
    ///   triangle's sides L of the first vertex. The gradient is at most 2 dz L / area2 (dz the
    ///   vertices' depth range) and the doubled area at least 1 subpixel² (snapped vertices are
    ///   integers), so each term is at most 2 dz L² <= 2^25 dz for L <= 2^12 subpixels
    ///   (kDepthTestedVoxelPixels times sqrt 2, under 16 pixels). The gradients' rounding and the
    ///   sum's three then cost at most 16 dz + 2^-21.
    double hiddenDepthMargin(double nearestZ, double farthestZ, double nearestW) const {
        const double zMagnitude = std::max(std::abs(nearestZ), std::abs(farthestZ));
        const double cornerError = (clipZError_ + zMagnitude * clipWError_) / nearestW;
        const double depthRange = farthestZ - nearestZ + 2.0 * cornerError;
        return cornerError + 16.0 * depthRange + kPlaneRounding;
    }

    static constexpr double kTransformRounding = 0x1p-20;  // sixteen roundings of 2^-24
    static constexpr double kPlaneRounding = 0x1p-21;      // the plane sum's roundings of terms up to 1

    const SampleFootprint& f_;
    const DepthFootprint* depth_;
    double clipZError_ = 0.0, clipWError_ = 0.0;
    glm::dvec4 origin_, step_[3];
    double halfWidth_ = 0.0, halfHeight_ = 0.0;
    glm::dvec4 halfExtent_{0.0};
};

}  // namespace

void expandVoxelFaces(const VoxelModel& model, const BlockVoxels& block, const glm::dvec3& camera, FaceMesh& out,
                      const glm::vec3* overrideColor, const VoxelRegion* region, const SampleFootprint* footprint,
                      const DepthFootprint* depth) {
    const VoxelBoxes boxes(model, block.level, block.coord);
    std::optional<FaceFootprints> footprints;
    if (footprint) footprints.emplace(*footprint, boxes, model.blockSize, depth);
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
            bool behind = false;
            const uint8_t covering = footprints->mayCoverSamples(position, emit, behind);
            (behind ? out.facesBehindDepth : out.facesBetweenSamples) += uint64_t(__builtin_popcount(emit ^ covering));
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
