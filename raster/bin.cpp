#include "raster/bin.h"

#include "raster/coarse.h"

namespace cuberille::raster {
namespace {

// Calls visit(tile) for every tile the triangle may cover.
template <class Visit>
void forEachCoveredTile(const TriangleSetup& t, const TileGrid& grid, const SamplePattern& sp,
                        Visit&& visit) {
    const int tx0 = t.pixelMinX / kTileSizePixels, tx1 = t.pixelMaxX / kTileSizePixels;
    const int ty0 = t.pixelMinY / kTileSizePixels, ty1 = t.pixelMaxY / kTileSizePixels;
    const bool singleTile = tx0 == tx1 && ty0 == ty1;
    for (int ty = ty0; ty <= ty1; ++ty) {
        for (int tx = tx0; tx <= tx1; ++tx) {
            if (!singleTile) {
                const PixelRect r{std::max(t.pixelMinX, tx * kTileSizePixels),
                                  std::max(t.pixelMinY, ty * kTileSizePixels),
                                  std::min(t.pixelMaxX, tx * kTileSizePixels + kTileSizePixels - 1),
                                  std::min(t.pixelMaxY, ty * kTileSizePixels + kTileSizePixels - 1)};
                if (classifyPixelRect(t, r, sp) == BlockClass::Empty) continue;
            }
            visit(ty * grid.tilesX + tx);
        }
    }
}

}  // namespace

void binTriangles(TriangleBatch& batch, const TileGrid& grid, const SamplePattern& samples) {
    const int tiles = grid.tileCount();
    batch.tileOffsets.assign(tiles + 1, 0);
    uint32_t* counts = batch.tileOffsets.data() + 1;
    for (const TriangleSetup& t : batch.triangles)
        forEachCoveredTile(t, grid, samples, [&](int tile) { ++counts[tile]; });
    for (int i = 0; i < tiles; ++i) batch.tileOffsets[i + 1] += batch.tileOffsets[i];

    batch.tileTriangles.resize(batch.tileOffsets[tiles]);
    std::vector<uint32_t> cursor(batch.tileOffsets.begin(), batch.tileOffsets.end() - 1);
    for (uint32_t i = 0; i < batch.triangles.size(); ++i)
        forEachCoveredTile(batch.triangles[i], grid, samples,
                           [&](int tile) { batch.tileTriangles[cursor[tile]++] = i; });
    batch.counters.binEntries += batch.tileTriangles.size();
}

}  // namespace cuberille::raster
