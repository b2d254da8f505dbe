#include "raster/stats.h"

namespace cuberille::raster {

StageCounters& StageCounters::operator+=(const StageCounters& o) {
    verticesShaded += o.verticesShaded;
    trianglesIn += o.trianglesIn;
    trianglesInvalid += o.trianglesInvalid;
    trianglesClipRejected += o.trianglesClipRejected;
    trianglesClipped += o.trianglesClipped;
    clippedTrianglesOut += o.clippedTrianglesOut;
    trianglesDegenerate += o.trianglesDegenerate;
    trianglesCulled += o.trianglesCulled;
    trianglesNoSamples += o.trianglesNoSamples;
    trianglesSetUp += o.trianglesSetUp;
    binEntries += o.binEntries;
    smallTriangleEntries += o.smallTriangleEntries;
    blocksEmpty += o.blocksEmpty;
    blocksPartial += o.blocksPartial;
    blocksFull += o.blocksFull;
    blocksDepthCulled += o.blocksDepthCulled;
    samplesTested += o.samplesTested;
    samplesPassed += o.samplesPassed;
    pixelsShaded += o.pixelsShaded;
    varyingsInterpolated += o.varyingsInterpolated;
    textureSamples += o.textureSamples;
    lightEvaluations += o.lightEvaluations;
    specularGlossinessPixels += o.specularGlossinessPixels;
    dielectricSpecularPixels += o.dielectricSpecularPixels;
    clearcoatPixels += o.clearcoatPixels;
    sheenPixels += o.sheenPixels;
    transmissionPixels += o.transmissionPixels;
    environmentPixels += o.environmentPixels;
    pixelsAlphaTested += o.pixelsAlphaTested;
    pixelsBlended += o.pixelsBlended;
    return *this;
}

}  // namespace cuberille::raster
