// `cuberille accuracy`: the report's invariants on a small edge-dominated scene, and the image
// error measures it is built on.

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "apps/accuracy_command.h"
#include "apps/accuracy_report.h"
#include "apps/image_error.h"
#include "apps/image_io.h"
#include "tests/temp_paths.h"

namespace {

namespace fs = std::filesystem;
using namespace cuberille::apps;
using cuberille::raster::Image;

Image flatImage(int width, int height, float value) {
    Image im;
    im.width = width;
    im.height = height;
    im.rgba.assign(size_t(width) * height * 4, value);
    return im;
}

fs::path tempDir(const std::string& name) {
    const fs::path dir = cuberille::testing::uniqueTempPath("accuracy-" + name);
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

// Thin slivers and long edges at many slopes: almost every covered pixel is an edge pixel, where
// only more samples help.
fs::path writeEdgeScene(const fs::path& dir) {
    std::ofstream out(dir / "edges.tri");
    for (int i = 0; i < 12; ++i) {
        const double x = 2 + 3.7 * i, slope = 0.3 + 0.11 * i;
        out << x << " 1 " << x + 2.3 << " 1.5 " << x + 30 * slope * 0.2 << " 30.5 " << 0.2 + 0.06 * i << "\n";
    }
    out << "1.5 20.2 46.5 24.9 1.2 22.7 1\n";
    return dir / "edges.tri";
}

class AccuracyReportOnEdges : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = new fs::path(tempDir("edges"));
        AccuracyOptions o;
        o.scene = writeEdgeScene(*dir_).string();
        o.outDir = *dir_ / "report";
        o.width = 48;
        o.height = 32;
        o.frames = 1;
        o.threads = 2;
        o.quiet = true;
        o.executable = CUBERILLE_BINARY;
        report_ = new AccuracyReport(runAccuracy(o));
    }
    static void TearDownTestSuite() {
        fs::remove_all(*dir_);
        delete report_;
        delete dir_;
    }
    static const AccuracyRow& row(const std::string& knob, const std::string& value) {
        for (const AccuracyRow& r : report_->rows)
            if (r.setting.knob == knob && r.setting.value == value) return r;
        ADD_FAILURE() << "no row " << knob << " " << value;
        return report_->rows.front();
    }
    static fs::path* dir_;
    static AccuracyReport* report_;
};
fs::path* AccuracyReportOnEdges::dir_ = nullptr;
AccuracyReport* AccuracyReportOnEdges::report_ = nullptr;

TEST_F(AccuracyReportOnEdges, ErrorFallsAsSamplesRise) {
    const double one = row("samples per pixel", "1").error.rmse, four = row("samples per pixel", "4").error.rmse,
                 sixteen = row("samples per pixel", "16").error.rmse;
    EXPECT_GT(one, 0.0);
    EXPECT_LT(four, one);
    EXPECT_LT(sixteen, four);
    EXPECT_GT(sixteen, 0.0);  // 16 samples are not 256
}

TEST_F(AccuracyReportOnEdges, GroundTruthAgainstItselfIsZero) {
    const AccuracyRow& truth = report_->rows.back();
    ASSERT_EQ(truth.setting.knob, "ground truth");
    EXPECT_EQ(truth.error.rmse, 0.0);
    EXPECT_EQ(truth.error.maxError, 0.0);
    EXPECT_TRUE(truth.deterministic);
    EXPECT_GE(truth.frameMs.size(), 2u);  // run twice even when one frame is asked for
    EXPECT_NE(truth.commandLine.find("--supersample 16"), std::string::npos);
}

TEST_F(AccuracyReportOnEdges, EveryRowHasTheCommandLineThatMadeIt) {
    for (const AccuracyRow& r : report_->rows) {
        EXPECT_EQ(r.commandLine.rfind("cuberille render ", 0), 0u) << r.commandLine;
        for (const std::string& arg : r.setting.args) EXPECT_NE(r.commandLine.find(arg), std::string::npos);
    }
    // Rerun one row's command line: the same image.
    const AccuracyRow& r = row("samples per pixel", "8");
    const fs::path again = *dir_ / "again.exr";
    std::string command = r.commandLine.substr(std::string("cuberille").size());
    const size_t out = command.find(" --out ");
    command = std::string(CUBERILLE_BINARY) + command.substr(0, out) + " --out " + again.string() + " --quiet";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    EXPECT_EQ(readImage(again).rgba, readImage(*dir_ / "report" / "renders" / (r.id + ".exr")).rgba);
}

TEST_F(AccuracyReportOnEdges, OnlySamplesPerPixelApplyToATriScene) {
    EXPECT_FALSE(report_->traits.threeD || report_->traits.textured || report_->traits.shadowed);
    for (const AccuracyRow& r : report_->rows)
        EXPECT_TRUE(r.setting.knob == "samples per pixel" || r.setting.knob == "preset" ||
                    r.setting.knob == "defaults" || r.setting.knob == "ground truth")
            << r.setting.knob;
}

TEST_F(AccuracyReportOnEdges, WritesCsvJsonAndHtmlWithEveryRow) {
    const fs::path dir = *dir_ / "report";
    std::ifstream csv(dir / "report.csv");
    std::string line;
    size_t lines = 0;
    while (std::getline(csv, line)) ++lines;
    EXPECT_EQ(lines, report_->rows.size() + 1);  // the header
    const nlohmann::json j = nlohmann::json::parse(std::ifstream(dir / "report.json"));
    ASSERT_EQ(j.at("rows").size(), report_->rows.size());
    EXPECT_EQ(j.at("threads").get<int>(), 2);
    std::stringstream html;
    html << std::ifstream(dir / "index.html").rdbuf();
    size_t plots = 0;
    for (size_t at = 0; (at = html.str().find("<svg", at)) != std::string::npos; ++at) ++plots;
    EXPECT_EQ(plots, 2u);
    for (const AccuracyRow& r : report_->rows) {
        EXPECT_TRUE(fs::exists(dir / "crops" / (r.id + ".png"))) << r.id;
        EXPECT_NE(html.str().find(r.id + ".png"), std::string::npos) << r.id;
    }
    // The front's fastest point is the fastest row, and the truth (zero error) is on it.
    EXPECT_TRUE(report_->rows.back().pareto);
}

// What a distributed runner does (python/cuberille/dask): plan, each run rendered on its own and
// its row sent back as JSON, then the report finished from rows whose images it reads back. Each
// row's error, worst region and image are those of the report made in one process.
TEST_F(AccuracyReportOnEdges, RunsTakenApartAndSentAsJsonGiveTheSameReport) {
    AccuracyOptions o = report_->options;
    o.outDir = *dir_ / "apart";
    AccuracyPlan plan = planAccuracy(o);
    std::vector<AccuracyRow> rows;
    for (const AccuracyRun& run : plan.runs) {
        const AccuracyRun sent = accuracyRunFromJson(nlohmann::json::parse(accuracyRunJson(run).dump()));
        EXPECT_EQ(sent.setting.args, run.setting.args);
        AccuracyRow row = runAccuracySetting(plan.report.options, sent);
        EXPECT_EQ(row.comparedWithTruth, run.groundTruth) << run.id;  // the others are compared by finishAccuracy
        rows.push_back(accuracyRowFromJson(nlohmann::json::parse(accuracyRowJson(row).dump())));
        EXPECT_EQ(rows.back().frameMs, row.frameMs);
        EXPECT_EQ(rows.back().commandLine, row.commandLine);
    }
    const AccuracyReport apart = finishAccuracy(std::move(plan), std::move(rows));
    ASSERT_EQ(apart.rows.size(), report_->rows.size());
    for (size_t i = 0; i < apart.rows.size(); ++i) {
        const AccuracyRow &a = apart.rows[i], &b = report_->rows[i];
        EXPECT_EQ(a.id, b.id);
        EXPECT_EQ(a.setting.knob, b.setting.knob);
        EXPECT_EQ(a.setting.value, b.setting.value);
        EXPECT_EQ(a.error.rmse, b.error.rmse) << a.id;
        EXPECT_EQ(a.error.maxError, b.error.maxError) << a.id;
        EXPECT_EQ(a.error.shareOver1, b.error.shareOver1) << a.id;
        EXPECT_EQ(a.worst.x, b.worst.x) << a.id;
        EXPECT_EQ(a.worst.y, b.worst.y) << a.id;
        EXPECT_EQ(readImage(o.outDir / "renders" / (a.id + ".exr")).rgba,
                  readImage(*dir_ / "report" / "renders" / (b.id + ".exr")).rgba)
            << a.id;
    }
    EXPECT_TRUE(fs::exists(o.outDir / "report.csv"));
    EXPECT_EQ(apart.rows.back().error.rmse, 0.0);
}

// A row's memory is its run's own peak: not wait4's ru_maxrss, which on Linux carries the resident
// set of the process that spawned the run (this test's, grown by 512 MiB first).
TEST_F(AccuracyReportOnEdges, PeakMemoryIsTheRunsOwnNotThatOfTheProcessThatSpawnedIt) {
    constexpr size_t kParentBytes = size_t(512) << 20;
    std::vector<char> held(kParentBytes);
    for (size_t i = 0; i < held.size(); i += 4096) held[i] = char(i);  // resident, not only reserved
    AccuracyRun run;
    run.setting.args = {"--msaa", "1"};
    run.id = "memory-of-one-run";
    const AccuracyRow row = runAccuracySetting(report_->options, run);
    const nlohmann::json stats = nlohmann::json::parse(std::ifstream(report_->options.outDir / "logs" / (run.id + ".json")));
    EXPECT_EQ(row.peakMib, stats.at("process").at("peakResidentBytes").get<double>() / (1024.0 * 1024.0));
    EXPECT_GT(row.peakMib, 1.0);
    EXPECT_LT(row.peakMib, double(kParentBytes >> 20));  // a 48x32 render of 13 triangles
    EXPECT_EQ(held[4096], char(4096));
}

TEST(AccuracySweep, CoversTheKnobsThatApplyAroundTheBalancedPreset) {
    SceneTraits all;
    all.threeD = all.textured = all.shadowed = true;
    std::set<std::string> knobs;
    for (const AccuracySetting& s : accuracySweep(all, false)) knobs.insert(s.knob);
    EXPECT_EQ(knobs, (std::set<std::string>{"samples per pixel", "texture filter", "shadow mode", "map shadow-map size",
                                            "hybrid shadow-map size", "depth precision", "renderer", "preset", "defaults",
                                            "ground truth"}));
    SceneTraits voxel;
    voxel.voxel = true;
    voxel.voxelResolutions = {256, 128, 64};
    const std::vector<AccuracySetting> v = accuracySweep(voxel, false);
    EXPECT_EQ(v.back().knob, "ground truth");
    bool lod = false;
    std::vector<std::string> resolutions;
    for (const AccuracySetting& s : v) {
        lod = lod || s.knob == "LOD pixel error";
        if (s.knob != "voxel resolution") continue;
        resolutions.push_back(s.value);
        const bool capped = std::find(s.args.begin(), s.args.end(), "--voxel-resolution") != s.args.end();
        EXPECT_EQ(capped, s.value != "256");  // the finest is the model as it is
    }
    EXPECT_TRUE(lod);
    EXPECT_EQ(resolutions, (std::vector<std::string>{"64", "128", "256"}));
    for (const std::string& a : v.back().args) EXPECT_NE(a, "--shadows");  // no shadow knob for voxels
}

// A 3D scene's sweep compares the rasterizer's visibility with the camera rays' through each
// structure (the same image, another time); scenes without camera rays get no such rows.
/// The renderer knob's values for a scene kind into `values`, checking each setting's arguments.
void rendererKnobValues(const SceneTraits& traits, std::vector<std::string>& values) {
    for (const AccuracySetting& s : accuracySweep(traits, false)) {
        const auto renderer = std::find(s.args.begin(), s.args.end(), "--renderer");
        if (s.knob != "renderer") {
            EXPECT_EQ(renderer, s.args.end()) << s.knob << " " << s.value << ": the balanced preset rasterizes";
            continue;
        }
        values.push_back(s.value);
        if (s.value == "raster") {
            EXPECT_EQ(renderer, s.args.end());
            continue;
        }
        ASSERT_NE(renderer, s.args.end());
        ASSERT_LT(renderer + 3, s.args.end());
        EXPECT_EQ(renderer[1], "raytrace");
        EXPECT_EQ(renderer[2], "--accel");
        EXPECT_EQ("raytrace, " + renderer[3], s.value);
    }
}

TEST(AccuracySweep, TheRendererKnobSetsRaysThroughEachStructureFor3dScenesAndVoxelModels) {
    SceneTraits threeD, voxel;
    threeD.threeD = true;
    voxel.voxel = true;
    std::vector<std::string> forThreeD, forVoxel, forTri;
    rendererKnobValues(threeD, forThreeD);
    rendererKnobValues(voxel, forVoxel);
    rendererKnobValues(SceneTraits{}, forTri);
    EXPECT_EQ(forThreeD, (std::vector<std::string>{"raster", "raytrace, bvh", "raytrace, grid"}));
    EXPECT_EQ(forVoxel, (std::vector<std::string>{"raster", "raytrace, bvh", "raytrace, kdtree", "raytrace, octree", "raytrace, bvh8"}));
    EXPECT_TRUE(forTri.empty());  // a 2D .tri scene has no rays
}

TEST(AccuracySweep, AmbientOcclusionIsSweptInEverySettingWhenAsked) {
    SceneTraits threeD;
    threeD.threeD = threeD.shadowed = true;
    for (const AccuracySetting& s : accuracySweep(threeD, false))
        EXPECT_EQ(std::find(s.args.begin(), s.args.end(), "--ao"), s.args.end()) << s.knob << " " << s.value;
    const std::vector<AccuracySetting> sweep = accuracySweep(threeD, false, 8);
    std::vector<std::string> rays;
    for (const AccuracySetting& s : sweep) {
        if (s.knob == "defaults") continue;  // what render does with no option: no occlusion
        const auto ao = std::find(s.args.begin(), s.args.end(), "--ao");
        ASSERT_NE(ao, s.args.end()) << s.knob << " " << s.value;
        ASSERT_NE(ao + 1, s.args.end());
        if (s.knob == "ambient occlusion rays") {
            rays.push_back(ao[1]);
            EXPECT_EQ(ao[1], s.value);
        } else if (s.knob == "ground truth" || (s.knob == "preset" && s.value == "exact")) {
            EXPECT_EQ(ao[1], std::to_string(kTruthOcclusionRays)) << s.knob;
        } else if (s.knob == "preset" && s.value == "fast") {
            EXPECT_EQ(ao[1], "1");
        } else {
            EXPECT_EQ(ao[1], "8") << s.knob << " " << s.value << ": the balanced preset's rays";
        }
    }
    EXPECT_EQ(rays, (std::vector<std::string>{"1", "4", "16", "64"}));
    SceneTraits voxel;
    voxel.voxel = true;
    for (const AccuracySetting& s : accuracySweep(voxel, false, 8))
        EXPECT_EQ(std::find(s.args.begin(), s.args.end(), "--ao"), s.args.end()) << "voxel models take no --ao";
}

TEST(AccuracyProbe, FindsTexturesAndShadowCastingLightsInTheDemoScene) {
    const fs::path dir = tempDir("probe");
    AccuracyOptions o;
    o.scene = "demo";
    o.outDir = dir;
    o.executable = CUBERILLE_BINARY;
    fs::create_directories(dir / "logs");
    const SceneTraits t = probeScene(o);
    EXPECT_TRUE(t.threeD && t.textured && t.shadowed);
    EXPECT_FALSE(t.voxel);
    fs::remove_all(dir);
}

TEST(ImageError, IdenticalImagesHaveZeroErrorAndInfinitePsnr) {
    const ImageError e = compareImages(flatImage(5, 4, 0.3f), flatImage(5, 4, 0.3f));
    EXPECT_EQ(e.rmse, 0.0);
    EXPECT_TRUE(std::isinf(e.psnrDb));
    EXPECT_EQ(e.shareOver1, 0.0);
}

TEST(ImageError, OnePixelOffIsMeasuredOnEncodedValues) {
    Image a = flatImage(4, 4, 0.0f), b = flatImage(4, 4, 0.0f);
    b.pixel(2, 1)[0] = 1.0f;  // one channel of one pixel: encoded 0 -> 1
    const ImageError e = compareImages(a, b);
    EXPECT_DOUBLE_EQ(e.rmse, std::sqrt(1.0 / 48.0));
    EXPECT_DOUBLE_EQ(e.maxError, 1.0);
    EXPECT_DOUBLE_EQ(e.shareOver1, 1.0 / 16.0);
    EXPECT_DOUBLE_EQ(e.shareOver8, 1.0 / 16.0);
    b.pixel(2, 1)[0] = 0.0005f;  // encoded 0.00646: over 1/255, under 8/255
    const ImageError small = compareImages(a, b);
    EXPECT_DOUBLE_EQ(small.shareOver1, 1.0 / 16.0);
    EXPECT_EQ(small.shareOver8, 0.0);
}

TEST(ImageError, WorstRegionFindsAPlantedBlock) {
    Image a = flatImage(40, 30, 0.5f), b = flatImage(40, 30, 0.5f);
    for (int y = 17; y < 23; ++y)
        for (int x = 25; x < 31; ++x) b.pixel(x, y)[1] = 0.9f;
    const PixelRect r = worstRegion(a, b, 6);
    EXPECT_EQ(r.x, 25);
    EXPECT_EQ(r.y, 17);
    EXPECT_EQ(r.width, 6);
    const Image crop = comparisonCrop(a, b, r, 4);
    EXPECT_EQ(crop.height, 24);
    EXPECT_GT(crop.width, 3 * 24);
    EXPECT_THROW(compareImages(a, flatImage(4, 4, 0.0f)), std::runtime_error);
}

}  // namespace
