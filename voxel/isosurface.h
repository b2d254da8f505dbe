#pragma once
// Iso-surface voxels from a sampled volume (Chajdas 2015, section 3.1.3). A voxel is emitted for
// every sample that is inside (value >= iso) and has a 6-neighbour outside; samples beyond the
// volume count as outside, so the surface of a volume filled to its edge is closed. The active
// faces are exactly the faces towards outside neighbours. Normals point outwards, from the
// gradient estimated by linear regression over the 3×3×3 neighbourhood (Neumann et al. 2000:
// robust on near-binary volumes, where central differences give staircase normals), or by central
// differences as an option. The volume is processed in 64³ blocks in parallel; a block whose
// samples and border are all inside or all outside is skipped without looking further.
//
// The grid: voxel (i, j, k) stands for sample (i, j, k); resolution is the smallest power of two
// covering the largest dimension, origin 0 and extent = resolution, in sample units.

#include <cstdint>
#include <string>
#include <string_view>

#include "voxel/voxel_model.h"

namespace cuberille::voxel {

enum class SampleType { U8, U16, F32 };
enum class GradientEstimator { LinearRegression, CentralDifferences };

struct VolumeDesc {
    glm::uvec3 dims{0};
    SampleType type = SampleType::U8;
};

size_t sampleBytes(SampleType t);

struct IsosurfaceOptions {
    double iso = 0.5;
    GradientEstimator gradient = GradientEstimator::LinearRegression;
};

struct IsosurfaceStats {
    uint64_t samples = 0, blocks = 0, blocksSkipped = 0, voxels = 0;
    double extractMs = 0;
};

/// samples: dims.x·dims.y·dims.z values, x fastest, little-endian. Throws std::invalid_argument
/// when the size does not match (callers check files first, to name them).
VoxelModel extractIsosurface(std::string_view samples, const VolumeDesc& volume, const IsosurfaceOptions& options,
                             IsosurfaceStats* stats = nullptr);

}  // namespace cuberille::voxel
