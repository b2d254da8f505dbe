#pragma once
// Named counters and timings of every stage. Counters are integers summed from per-batch and
// per-tile partial counts, so they are the same for every thread count.

#include <cstdint>
#include <vector>

namespace cuberille::raster {

struct StageCounters {
    // vertex
    uint64_t verticesShaded = 0;
    // clip
    uint64_t trianglesIn = 0;
    uint64_t trianglesInvalid = 0;       // NaN/Inf coordinates: dropped
    uint64_t trianglesClipRejected = 0;  // wholly outside near, far or the guard band
    uint64_t trianglesClipped = 0;       // cut against a plane
    uint64_t clippedTrianglesOut = 0;    // fan triangles produced by clipping
    // setup
    uint64_t trianglesDegenerate = 0;
    uint64_t trianglesCulled = 0;
    uint64_t trianglesNoSamples = 0;
    uint64_t trianglesSetUp = 0;
    // bin
    uint64_t binEntries = 0;  // (triangle, tile) pairs
    // coarse
    uint64_t smallTriangleEntries = 0;  // entries that skipped the coarse stage
    uint64_t blocksEmpty = 0;
    uint64_t blocksPartial = 0;
    uint64_t blocksFull = 0;
    uint64_t blocksDepthCulled = 0;  // non-empty blocks rejected by hierarchical Z
    // fine, depth, shade, output merge
    uint64_t samplesTested = 0;  // covered samples that met the depth test
    uint64_t samplesPassed = 0;
    uint64_t pixelsShaded = 0;
    // shade and output merge, per effect: how often each ran (zero when a scene lacks it)
    uint64_t varyingsInterpolated = 0;  // floats interpolated, summed over shaded pixels
    uint64_t textureSamples = 0;        // filtered texture fetches
    uint64_t lightEvaluations = 0;      // (pixel, light) pairs lit
    uint64_t specularGlossinessPixels = 0;  // pixels whose material is specular-glossiness (KHR_materials_pbrSpecularGlossiness)
    uint64_t dielectricSpecularPixels = 0;  // pixels whose material has KHR_materials_specular
    uint64_t clearcoatPixels = 0;           // pixels under a clear coat (KHR_materials_clearcoat)
    uint64_t sheenPixels = 0;               // pixels with a sheen (KHR_materials_sheen)
    uint64_t transmissionPixels = 0;        // pixels seen through (KHR_materials_transmission)
    uint64_t environmentPixels = 0;         // pixels lit by an environment (image-based lighting)
    uint64_t pixelsAlphaTested = 0;     // alpha-mask pixels tested against the cutoff
    uint64_t pixelsBlended = 0;         // pixels over-blended onto the target

    StageCounters& operator+=(const StageCounters& o);
};

struct StageTimes {
    double vertexMs = 0;    // wall time
    double frontEndMs = 0;  // clip + setup + bin, wall time
    double backEndMs = 0;   // coarse + fine + depth + shade + output merge, wall time
    double resolveMs = 0;
    double frameMs = 0;
};

struct PipelineStats {
    StageCounters counters;
    StageTimes times;
    std::vector<uint64_t> occlusionSamplesPassed;  // per occlusion slot
    uint64_t flushes = 0;
};

}  // namespace cuberille::raster
