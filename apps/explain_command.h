#pragma once
// `cuberille explain`: the rasterization pipeline shown stage by stage for a `.tri` scene or one
// triangle, as magnified images with the pixel grid, pixel centres and sample points drawn
// (docs/pipeline.md walks through them). Every picture is read from the real stages: set-up's
// snapped vertices, pixel bounds and edge functions (raster/setup.h, raster/fine.h), the coarse
// stage's block classes and the framebuffer's samples after the real pipeline ran.
//
// Stages shown: 1-setup, 2-coarse, 3-edges (+ 3-edges.csv, the edge values along one row),
// 4-coverage-N for N = 1, 2, 4, 8, 16, 5-shaded (per-sample colours at 16 samples), 6-resolve-N
// for N = 1, 4, 16. `.tri` scenes have no depth test (DESIGN.md), so no depth stage is drawn.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "raster/resolve.h"
#include "scene/tri_scene.h"

namespace cuberille::apps {

/// The triangle docs/pipeline.md walks through (its pictures are golden images too).
inline constexpr const char* kExplainTriangle = "1.3 1.7 14.6 4.2 5.1 12.8";

struct ExplainOptions {
    std::string scene;     // a .tri file, or empty with `triangle`
    std::string triangle;  // "x0 y0 x1 y1 x2 y2": one triangle of value 1
    std::filesystem::path outDir;
    int width = 0, height = 0;  // the framebuffer; 0: the scene's bounds and a margin
    int scale = 24;             // image pixels per framebuffer pixel
    int row = -1;               // the row whose edge values 3-edges shows; -1: the middle of the first triangle
    int triangleIndex = 0;      // the triangle whose set-up and edge functions are drawn
    bool quiet = false;
};

struct ExplainResult {
    std::vector<std::pair<std::string, raster::Image>> images;  // stage name, picture
    std::string edgeCsv;                                        // x, E0, E1, E2, covered
};

/// Draws every stage; throws scene::InputError on bad options.
ExplainResult explainScene(const scene::TriScene& scene, const ExplainOptions& options);

/// The whole subcommand: writes DIR/<stage>.png (and 3-edges.csv). Returns the exit code.
int runExplainCommand(const ExplainOptions& options);

}  // namespace cuberille::apps
