#include "voxel/isosurface.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "raster/clock.h"
#include "raster/parallel.h"
#include "voxel/morton.h"
#include "voxel/packing.h"

namespace cuberille::voxel {
namespace {

/// Read access to the samples as doubles, with the two border rules: clamped to the edge (for
/// gradients) and "outside" beyond the volume (for classification).
class Volume {
public:
    Volume(std::string_view bytes, const VolumeDesc& d) : bytes_(bytes), d_(d), stride_(sampleBytes(d.type)) {}

    double at(int x, int y, int z) const {
        const size_t i = (size_t(z) * d_.dims.y + size_t(y)) * d_.dims.x + size_t(x);
        const char* p = bytes_.data() + i * stride_;
        switch (d_.type) {
            case SampleType::U8: return double(uint8_t(*p));
            case SampleType::U16: {
                uint16_t v;
                std::memcpy(&v, p, 2);
                return double(v);
            }
            case SampleType::F32: {
                float v;
                std::memcpy(&v, p, 4);
                return double(v);
            }
        }
        return 0.0;
    }
    double clamped(int x, int y, int z) const {
        return at(std::clamp(x, 0, int(d_.dims.x) - 1), std::clamp(y, 0, int(d_.dims.y) - 1),
                  std::clamp(z, 0, int(d_.dims.z) - 1));
    }
    bool contains(int x, int y, int z) const {
        return x >= 0 && y >= 0 && z >= 0 && x < int(d_.dims.x) && y < int(d_.dims.y) && z < int(d_.dims.z);
    }
    bool inside(int x, int y, int z, double iso) const { return contains(x, y, z) && at(x, y, z) >= iso; }

private:
    std::string_view bytes_;
    VolumeDesc d_;
    size_t stride_;
};

/// The gradient by least squares fit of a linear function over the 26-neighbourhood, weighted by
/// inverse distance: each component is sum(w f d_k) / sum(w d_k²).
glm::dvec3 regressionGradient(const Volume& v, int x, int y, int z) {
    glm::dvec3 num(0.0), den(0.0);
    for (int dz = -1; dz <= 1; ++dz)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dx = -1; dx <= 1; ++dx) {
                if (!dx && !dy && !dz) continue;
                const glm::dvec3 d(dx, dy, dz);
                const double w = 1.0 / glm::length(d);
                num += w * v.clamped(x + dx, y + dy, z + dz) * d;
                den += w * d * d;
            }
    return num / den;
}

glm::dvec3 centralGradient(const Volume& v, int x, int y, int z) {
    return 0.5 * glm::dvec3(v.clamped(x + 1, y, z) - v.clamped(x - 1, y, z), v.clamped(x, y + 1, z) - v.clamped(x, y - 1, z),
                            v.clamped(x, y, z + 1) - v.clamped(x, y, z - 1));
}

/// Whether the block and its one-sample border hold both inside and outside samples (outside
/// the volume counts as outside).
bool blockCrossesIso(const Volume& v, const glm::ivec3& lo, const glm::ivec3& hi, double iso) {
    bool in = false, out = false;
    for (int z = lo.z - 1; z <= hi.z; ++z)
        for (int y = lo.y - 1; y <= hi.y; ++y)
            for (int x = lo.x - 1; x <= hi.x; ++x) {
                (v.inside(x, y, z, iso) ? in : out) = true;
                if (in && out) return true;
            }
    return false;
}

}  // namespace

size_t sampleBytes(SampleType t) { return t == SampleType::U8 ? 1 : t == SampleType::U16 ? 2 : 4; }

VoxelModel extractIsosurface(std::string_view samples, const VolumeDesc& d, const IsosurfaceOptions& o,
                             IsosurfaceStats* statsOut) {
    const uint64_t count = uint64_t(d.dims.x) * d.dims.y * d.dims.z;
    if (count == 0 || samples.size() != count * sampleBytes(d.type))
        throw std::invalid_argument("volume size does not match its dimensions");
    const double t0 = raster::nowMs();
    uint32_t resolution = kMinResolution;
    while (resolution < std::max({d.dims.x, d.dims.y, d.dims.z})) resolution *= 2;
    if (resolution > kMaxResolution) throw std::invalid_argument("volume larger than the largest grid (65536)");
    VoxelModel model;
    model.grid = {resolution, glm::dvec3(0.0), double(resolution)};
    model.blockSize = std::min(kBlockSize, resolution);
    const Volume volume(samples, d);

    const glm::uvec3 blocks = (d.dims + model.blockSize - 1u) / model.blockSize;
    std::vector<glm::uvec3> order;
    for (uint32_t z = 0; z < blocks.z; ++z)
        for (uint32_t y = 0; y < blocks.y; ++y)
            for (uint32_t x = 0; x < blocks.x; ++x) order.push_back({x, y, z});
    std::sort(order.begin(), order.end(), [](auto& a, auto& b) { return mortonOf(a) < mortonOf(b); });

    std::vector<VoxelBlock> out(order.size());
    std::vector<uint8_t> skipped(order.size(), 0);
    raster::parallelFor(order.size(), [&](size_t bi) {
        const glm::ivec3 lo(order[bi] * model.blockSize);
        const glm::ivec3 hi = glm::min(lo + int(model.blockSize), glm::ivec3(d.dims));
        if (!blockCrossesIso(volume, lo, hi, o.iso)) {
            skipped[bi] = 1;
            return;
        }
        VoxelBlock& b = out[bi];
        b.coord = order[bi];
        std::vector<std::pair<uint64_t, uint32_t>> found;  // (Morton, index) so voxels come in Morton order
        for (int z = lo.z; z < hi.z; ++z)
            for (int y = lo.y; y < hi.y; ++y)
                for (int x = lo.x; x < hi.x; ++x) {
                    if (!volume.inside(x, y, z, o.iso)) continue;
                    uint8_t faces = 0;
                    if (!volume.inside(x + 1, y, z, o.iso)) faces |= kFacePosX;
                    if (!volume.inside(x - 1, y, z, o.iso)) faces |= kFaceNegX;
                    if (!volume.inside(x, y + 1, z, o.iso)) faces |= kFacePosY;
                    if (!volume.inside(x, y - 1, z, o.iso)) faces |= kFaceNegY;
                    if (!volume.inside(x, y, z + 1, o.iso)) faces |= kFacePosZ;
                    if (!volume.inside(x, y, z - 1, o.iso)) faces |= kFaceNegZ;
                    if (!faces) continue;
                    const glm::dvec3 g = o.gradient == GradientEstimator::LinearRegression
                                             ? regressionGradient(volume, x, y, z)
                                             : centralGradient(volume, x, y, z);
                    glm::dvec3 n = -g;
                    if (!(glm::length(n) > 0.0))  // flat neighbourhood: the open faces' directions
                        n = glm::dvec3((faces & kFacePosX ? 1 : 0) - (faces & kFaceNegX ? 1 : 0),
                                       (faces & kFacePosY ? 1 : 0) - (faces & kFaceNegY ? 1 : 0),
                                       (faces & kFacePosZ ? 1 : 0) - (faces & kFaceNegZ ? 1 : 0));
                    const double len = glm::length(n);
                    const glm::uvec3 local = glm::uvec3(x, y, z) - glm::uvec3(lo);
                    found.push_back({mortonOf(local), uint32_t(b.voxels.size())});
                    b.voxels.push_back(packVoxel(local.x, local.y, local.z, faces));
                    b.normals.push_back(packNormal1010102(len > 0.0 ? glm::vec3(n / len) : glm::vec3(0.0f)));
                    b.colors.push_back(0xFFFFFFFFu);
                }
        std::sort(found.begin(), found.end());
        VoxelBlock sorted;
        sorted.coord = b.coord;
        sorted.tightMin = glm::uvec3(model.blockSize);
        for (auto [key, i] : found) {
            sorted.voxels.push_back(b.voxels[i]);
            sorted.normals.push_back(b.normals[i]);
            sorted.colors.push_back(b.colors[i]);
            sorted.tightMin = glm::min(sorted.tightMin, voxelPositionInBlock(b.voxels[i]));
            sorted.tightMax = glm::max(sorted.tightMax, voxelPositionInBlock(b.voxels[i]));
        }
        b = std::move(sorted);
    });
    IsosurfaceStats stats;
    stats.samples = count;
    stats.blocks = order.size();
    for (size_t i = 0; i < out.size(); ++i) {
        stats.blocksSkipped += skipped[i];
        if (!out[i].voxels.empty()) model.blocks.push_back(std::move(out[i]));
    }
    stats.voxels = model.voxelCount();
    stats.extractMs = raster::nowMs() - t0;
    if (statsOut) *statsOut = stats;
    return model;
}

}  // namespace cuberille::voxel
