// The real scans in ../shared/data load and render without error. Skipped, with a message,
// when the folder is absent (a fresh clone outside the workplace).

#include <gtest/gtest.h>

#include <filesystem>

#include "apps/render_command.h"

namespace cuberille::testing {
namespace {

namespace fs = std::filesystem;

TEST(RealData, EveryScanLoadsAndRenders) {
    const fs::path scans = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data" / "scans";
    if (!fs::exists(scans)) GTEST_SKIP() << scans << " is absent; real-data checks skipped";
    int rendered = 0;
    for (const auto& entry : fs::recursive_directory_iterator(scans)) {
        const std::string name = entry.path().filename().string();
        if (!(name.ends_with(".ply") || name.ends_with(".ply.gz") || name.ends_with(".obj"))) continue;
        apps::RenderOptions o;
        o.scene = entry.path().string();
        o.width = 96;
        o.height = 64;
        o.quiet = true;
        const apps::RenderResult r = apps::renderScene(o);
        EXPECT_GT(r.sceneTriangles, 1000u) << name;
        EXPECT_GT(r.stats.counters.samplesPassed, 500u) << name << " should fill part of the frame";
        ++rendered;
    }
    EXPECT_GE(rendered, 3);
}

TEST(RealData, EveryGltfSampleLoadsAndRenders) {
    const fs::path data = fs::path(CUBERILLE_SOURCE_DIR) / ".." / "shared" / "data";
    if (!fs::exists(data / "gltf")) GTEST_SKIP() << data << " is absent; real-data checks skipped";
    int rendered = 0;
    for (const char* folder : {"gltf", "asset-generator"}) {
        for (const auto& entry : fs::recursive_directory_iterator(data / folder)) {
            const std::string name = entry.path().filename().string();
            if (!(name.ends_with(".gltf") || name.ends_with(".glb"))) continue;
            apps::RenderOptions o;
            o.scene = entry.path().string();
            o.width = 64;
            o.height = 48;
            o.quiet = true;
            try {
                const apps::RenderResult r = apps::renderScene(o);
                // Material_AlphaMask_03 masks with alphaCutoff 1.1: by design nothing survives.
                const bool emptyByDesign = name == "Material_AlphaMask_03.gltf";
                if (r.sceneTriangles > 0 && !emptyByDesign) {
                    EXPECT_GT(r.stats.counters.samplesPassed, 0u) << name << " drew nothing";
                }
                if (emptyByDesign) {
                    EXPECT_EQ(r.stats.counters.samplesPassed, 0u) << name;
                }
            } catch (const std::exception& e) {
                ADD_FAILURE() << name << ": " << e.what();
            }
            ++rendered;
        }
    }
    EXPECT_GE(rendered, 15);
}

}  // namespace
}  // namespace cuberille::testing
