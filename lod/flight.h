#pragma once
// A flight through a streamed model (Chajdas 2015, section 4.8): frame after frame along a camera
// path, each frame streaming (take in what the I/O thread read, up to the upload limit), selecting,
// drawing and reading occlusion back, and recording where its time and bytes went — the
// per-frame measurements of figures 34-39. After the path, the last view can be rendered until
// loading settles, so the final image is the one every block resident would give.

#include <functional>
#include <vector>

#include "lod/streaming_blocks.h"
#include "lod/voxel_scene.h"
#include "raster/pipeline.h"
#include "scene/camera.h"

namespace cuberille::lod {

struct FlightFrame {
    int index = 0;
    bool settling = false;  // after the path: its last view again, until loading settles
    double frameMs = 0;     // the whole frame: the parts below
    double traversalMs = 0;  // block selection, residency and occlusion planning
    double ioWaitMs = 0;     // waiting for the I/O thread (settling only: frames on the path never wait)
    double uploadMs = 0;     // taking in loaded blocks and copying them into the pools
    double rasterMs = 0;     // voxel-face expansion, the draws and the pipeline
    StreamingFrameStats streaming;
    VoxelFrameStats voxel;
};

class Flight {
public:
    Flight(VoxelScene& scene, StreamingBlocks& blocks, const raster::FramebufferDesc& framebuffer,
           const VoxelRenderOptions& options);

    /// Renders one frame from `camera`; its image stays in pipeline() until the next frame.
    FlightFrame frame(const scene::Camera& camera, bool settling = false);
    /// Renders the camera's view until loading settles (or maxFrames), waiting on the I/O thread
    /// between frames instead of spinning.
    /// afterFrame, when given, sees each frame as it ends.
    std::vector<FlightFrame> settle(const scene::Camera& camera, int maxFrames,
                                    const std::function<void(const FlightFrame&)>& afterFrame = {});

    const raster::Pipeline& pipeline() const { return pipeline_; }
    int framesRendered() const { return frames_; }

private:
    VoxelScene& scene_;
    StreamingBlocks& blocks_;
    raster::FramebufferDesc framebuffer_;
    VoxelRenderOptions options_;
    raster::Pipeline pipeline_;
    int frames_ = 0;
};

}  // namespace cuberille::lod
