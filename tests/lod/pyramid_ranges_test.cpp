// The LOD pyramid built a range of blocks at a time (lod/pyramid_ranges.h): what a distributed
// voxelization writes must be the single-machine .cvox and voxel export byte for byte, for any
// plan, and no range may cut a subtree of its split level.

#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "lod/pyramid_ranges.h"
#include "scene/input_error.h"
#include "tests/lod/lod_test_support.h"
#include "tests/temp_paths.h"
#include "voxel/morton.h"
#include "voxel/partial_voxelization_file.h"
#include "voxel/voxel_export.h"

namespace cuberille {
namespace {

/// uniqueTempPath is one path per name and process: the files of these tests are numbered.
size_t nextTempFile() {
    static size_t next = 0;
    return next++;
}

struct WholeModelFiles {
    std::string cvox, exportText;
    lod::PyramidStats stats;
};

WholeModelFiles wholeModelFiles(const voxel::MeshView& view, const voxel::VoxelizeOptions& o, const lod::PyramidOptions& po) {
    voxel::VoxelModel m = voxel::voxelizeMesh(view, o);
    WholeModelFiles f;
    lod::buildLodPyramid(m, po, &f.stats);
    f.cvox = testing::cvoxBytes(m);
    std::ostringstream text;
    voxel::writeVoxelExport(m, text);
    f.exportText = text.str();
    return f;
}

/// Every step of a distributed voxelization in one process: the parts' indexes planned, each
/// range merged from every part into its range file, the ranges joined.
struct Joined {
    lod::PyramidRangePlan plan;
    std::string cvox, exportText;
    lod::PyramidStats stats;
    std::vector<std::filesystem::path> rangeFiles;
    size_t blocksRead = 0;  // over every range and part
};

Joined joinRanges(const std::vector<std::filesystem::path>& parts, const lod::PyramidOptions& po, size_t wantedRanges) {
    std::vector<std::pair<uint64_t, uint64_t>> index;
    voxel::VoxelModel header;
    for (const auto& p : parts) {
        const voxel::PartialVoxelizationIndex partIndex = voxel::readPartialVoxelizationIndex(p);
        index.insert(index.end(), partIndex.blocks.begin(), partIndex.blocks.end());
        header = partIndex.part.header;
        EXPECT_TRUE(voxel::readPartialVoxelization(p, 0, 0).blocks.empty());
    }
    Joined j;
    j.plan = lod::planPyramidRanges(index, lod::pyramidLevels(header.grid.resolution, header.blockSize, po), wantedRanges);
    for (size_t k = 0; k < j.plan.rangeCount(); ++k) {
        std::vector<voxel::PartialVoxelization> read;
        for (const auto& p : parts) {
            read.push_back(voxel::readPartialVoxelization(p, j.plan.rangeBegin(k), j.plan.rangeEnd(k)));
            for (const voxel::BlockPartial& b : read.back().blocks) {
                const uint64_t code = voxel::mortonOf(b.coord);
                EXPECT_TRUE(code >= j.plan.rangeBegin(k) && code < j.plan.rangeEnd(k));
            }
            j.blocksRead += read.back().blocks.size();
        }
        j.rangeFiles.push_back(testing::uniqueTempPath("range" + std::to_string(nextTempFile()) + ".cvxr"));
        std::ofstream out(j.rangeFiles.back(), std::ios::binary);
        lod::buildPyramidRange(voxel::mergePartialVoxelizations(std::move(read)), po, j.plan.splitLevel, out);
    }
    const lod::PyramidRangeJoin join(header, j.rangeFiles, po, j.plan);
    std::ostringstream cvox, text;
    join.write(cvox, &text);
    j.cvox = cvox.str(), j.exportText = text.str(), j.stats = join.stats();
    return j;
}

std::vector<std::filesystem::path> partFiles(const voxel::MeshView& view, const voxel::VoxelizeOptions& o,
                                             const std::vector<std::pair<size_t, size_t>>& runs) {
    std::vector<std::filesystem::path> files;
    for (const auto& [first, count] : runs) {
        files.push_back(testing::uniqueTempPath("part" + std::to_string(nextTempFile()) + ".cvxp"));
        std::ofstream out(files.back(), std::ios::binary);
        voxel::writePartialVoxelization(voxel::voxelizeChunks(view, o, first, count), out);
    }
    return files;
}

// The promise python/cuberille/dask makes: whatever the plan (one range, three, seven: split at the
// top, in the middle, at level 0), whatever the pyramid's options (every level, a cut pyramid, level 0 alone, serial
// simplification, hidden faces kept), with and without colours, the joined ranges are
// `cuberille voxelize`'s .cvox and export byte for byte, and report its pyramid's counts.
TEST(PyramidRanges, JoinedRangesWriteTheWholePyramidsBytesForAnyPlan) {
    std::mt19937 rng(5);
    const std::vector<testing::Triangle> tris = testing::icosphere(4, glm::dvec3(0.0), 2.0, testing::randomRotation(rng));
    std::vector<glm::vec3> colors;
    for (size_t i = 0; i < tris.size(); ++i) colors.push_back(glm::vec3(float(i % 7) / 6.0f, 0.5f, float(i % 4) / 3.0f));
    std::set<uint32_t> splitLevelsSeen;
    std::vector<lod::PyramidOptions> pyramids(5);
    pyramids[1].maxLevels = 2;
    pyramids[2].maxLevels = 1;
    pyramids[3].method = lod::SimplifyMethod::Serial;
    pyramids[4].clearHiddenFaces = false;
    for (const bool withColors : {false, true}) {
        const auto view = testing::viewOf(tris, 1000, withColors ? colors : std::vector<glm::vec3>{});
        voxel::VoxelizeOptions o;
        o.resolution = 256;  // 4 blocks a side: three levels
        const size_t n = view->chunkCount();
        ASSERT_GE(n, 4u);
        const auto parts = partFiles(*view, o, {{n / 2, n - n / 2}, {0, n / 2}});
        for (size_t p = 0; p < (withColors ? 1 : pyramids.size()); ++p) {
            const lod::PyramidOptions& po = pyramids[p];
            const WholeModelFiles whole = wholeModelFiles(*view, o, po);
            for (const size_t wanted : {size_t(1), size_t(3), size_t(7)}) {
                const Joined j = joinRanges(parts, po, wanted);
                SCOPED_TRACE("colours " + std::to_string(withColors) + ", pyramid options " + std::to_string(p) +
                             ", wanted " + std::to_string(wanted) + ": split level " + std::to_string(j.plan.splitLevel) +
                             ", " + std::to_string(j.plan.rangeCount()) + " ranges");
                splitLevelsSeen.insert(j.plan.splitLevel);
                EXPECT_LE(j.plan.rangeCount(), wanted);
                if (wanted > 1) {
                    EXPECT_GT(j.plan.rangeCount(), 1u);
                }
                EXPECT_TRUE(j.cvox == whole.cvox);  // not EXPECT_EQ: megabytes of bytes on failure
                EXPECT_EQ(j.cvox.size(), whole.cvox.size());
                EXPECT_TRUE(j.exportText == whole.exportText);
                EXPECT_EQ(j.stats.levels, whole.stats.levels);
                EXPECT_EQ(j.stats.blocksPerLevel, whole.stats.blocksPerLevel);
                EXPECT_EQ(j.stats.voxelsPerLevel, whole.stats.voxelsPerLevel);
                EXPECT_EQ(j.stats.skirtFaces, whole.stats.skirtFaces);
                EXPECT_EQ(j.stats.hiddenFacesCleared, whole.stats.hiddenFacesCleared);
                // Each part's blocks read once over all ranges: no range reads another's blocks.
                size_t partBlocks = 0;
                for (const auto& path : parts) partBlocks += voxel::readPartialVoxelization(path).blocks.size();
                EXPECT_EQ(j.blocksRead, partBlocks);
            }
        }
    }
    // The plans above split at level 0 (ranges of single blocks), in the middle (the join builds
    // a level) and at the top (one range builds all).
    EXPECT_EQ(splitLevelsSeen, (std::set<uint32_t>{0, 1, 2}));
}

// A range never cuts a subtree of its split level (its blocks up to level S are built from the
// range alone), the split level is the highest with enough subtrees, and the ranges together cover
// every block once, none empty; on random sets of blocks.
TEST(PyramidRanges, RangesStartOnSplitLevelSubtreesAndEachHoldsBlocks) {
    std::mt19937 rng(17);
    for (int trial = 0; trial < 300; ++trial) {
        const uint32_t levels = 1 + rng() % 6;
        const uint64_t codes = uint64_t(1) << (3 * (levels - 1));  // level-0 blocks of such a pyramid
        std::vector<std::pair<uint64_t, uint64_t>> blocks;
        const size_t count = 1 + rng() % 200;
        for (size_t i = 0; i < count; ++i) blocks.push_back({rng() % codes, 1 + rng() % 1000});
        const size_t wanted = 1 + rng() % 12;
        const lod::PyramidRangePlan plan = lod::planPyramidRanges(blocks, levels, wanted);
        const uint64_t subtree = uint64_t(1) << (3 * plan.splitLevel);
        ASSERT_LT(plan.splitLevel, levels);
        ASSERT_EQ(plan.rangeStarts.front(), 0u);
        ASSERT_LE(plan.rangeCount(), wanted);
        std::set<uint64_t> distinct;
        for (const auto& b : blocks) distinct.insert(b.first);
        auto subtreesAt = [&](uint32_t l) {
            std::set<uint64_t> s;
            for (uint64_t c : distinct) s.insert(c >> (3 * l));
            return s.size();
        };
        if (wanted > 1) {
            const size_t enough = std::min(2 * wanted, distinct.size());
            EXPECT_GE(subtreesAt(plan.splitLevel), enough);
            if (plan.splitLevel + 1 < levels) {
                EXPECT_LT(subtreesAt(plan.splitLevel + 1), enough);
            }
        }
        std::vector<size_t> perRange(plan.rangeCount(), 0);
        for (uint64_t c : distinct) {
            size_t k = 0;
            while (k < plan.rangeCount() && !(c >= plan.rangeBegin(k) && c < plan.rangeEnd(k))) ++k;
            ASSERT_LT(k, plan.rangeCount());
            ++perRange[k];
        }
        for (size_t k = 0; k < plan.rangeCount(); ++k) {
            EXPECT_EQ(plan.rangeBegin(k) % subtree, 0u);
            if (k > 0) {
                EXPECT_LT(plan.rangeBegin(k - 1), plan.rangeBegin(k));
            }
            EXPECT_GT(perRange[k], 0u) << "range " << k << " of " << plan.rangeCount();
        }
    }
}

// Range files given out of the plan's order, or cut short, are refused naming the file.
TEST(PyramidRanges, RangeFilesOutOfOrderOrCutShortAreRefusedNamingTheFile) {
    std::mt19937 rng(23);
    const auto view = testing::viewOf(testing::icosphere(3, glm::dvec3(0.0), 2.0, testing::randomRotation(rng)), 300);
    voxel::VoxelizeOptions o;
    o.resolution = 256;
    const auto parts = partFiles(*view, o, {{0, view->chunkCount()}});
    const Joined j = joinRanges(parts, {}, 3);
    ASSERT_EQ(j.plan.rangeCount(), 3u);
    const voxel::VoxelModel header = voxel::readPartialVoxelizationIndex(parts[0]).part.header;
    std::vector<std::filesystem::path> reversed(j.rangeFiles.rbegin(), j.rangeFiles.rend());
    try {
        lod::PyramidRangeJoin(header, reversed, {}, j.plan);
        ADD_FAILURE() << "ranges out of order were joined";
    } catch (const scene::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("out of Morton order"), std::string::npos) << e.what();
    }
    std::string bytes;
    {
        std::ifstream in(j.rangeFiles[1], std::ios::binary);
        bytes.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    }
    for (const size_t keep : {size_t(20), size_t(60), bytes.size() - 1}) {
        std::vector<std::filesystem::path> files = j.rangeFiles;
        files[1] = testing::uniqueTempPath("cut" + std::to_string(nextTempFile()) + ".cvxr");
        std::ofstream(files[1], std::ios::binary).write(bytes.data(), std::streamsize(keep));
        try {
            lod::PyramidRangeJoin(header, files, {}, j.plan);
            ADD_FAILURE() << "a range file cut to " << keep << " bytes was joined";
        } catch (const scene::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(files[1].string()), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace cuberille
