// The tool as a user meets it: exit codes, messages naming file and line, nothing written on
// failure, an earlier good output left untouched.

#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <span>
#include <sstream>
#include <sys/wait.h>

#include <zlib.h>

#include <nlohmann/json.hpp>

#include "apps/image_io.h"
#include "apps/render_command.h"
#include "tests/scene/gltf_builder.h"
#include "tests/scene/ply_builder.h"
#include "voxel/cvox_file.h"
#include "tests/temp_paths.h"

namespace {

namespace fs = std::filesystem;

struct CommandRun {
    int exitCode;
    std::string output;
};

CommandRun run(const std::string& args) {
    const std::string command = std::string(CUBERILLE_BINARY) + " " + args + " 2>&1";
    CommandRun r{-1, ""};
    FILE* pipe = popen(command.c_str(), "r");
    char buffer[512];
    while (pipe && fgets(buffer, sizeof buffer, pipe)) r.output += buffer;
    const int status = pipe ? pclose(pipe) : -1;
    r.exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

class Cli : public ::testing::Test {
protected:
    void SetUp() override {
        dir_ = cuberille::testing::uniqueTempPath(std::string("cli-") +
                                                  ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override { if (!getenv("KEEP_CLI_DIRS")) fs::remove_all(dir_); }
    fs::path write(const std::string& name, const std::string& text) {
        std::ofstream(dir_ / name) << text;
        return dir_ / name;
    }
    fs::path dir_;
};

TEST_F(Cli, RendersTriSceneToExrAndPng) {
    const fs::path scene = write("ok.tri", "1 1 30 2 5 20 1\n");
    for (const char* ext : {".exr", ".png"}) {
        const fs::path out = dir_ / (std::string("ok") + ext);
        const CommandRun r = run("render " + scene.string() + " --width 32 --height 24 --msaa 4 --out " +
                          out.string() + " --stats " + (dir_ / "s.json").string());
        EXPECT_EQ(r.exitCode, 0) << r.output;
        EXPECT_TRUE(fs::exists(out));
        EXPECT_TRUE(fs::exists(dir_ / "s.json"));
    }
}

// Start-up pays only for what the run uses (apps/oiio_module.h): the dynamic loader's own
// record (LD_DEBUG=files) of a PNG render names no OpenImageIO library, and that of an EXR
// render does, which is the check that the record can show it.
TEST_F(Cli, APngRenderNeverLoadsOpenImageIoAndAnExrRenderDoes) {
    const fs::path scene = write("ok.tri", "1 1 30 2 5 20 1\n");
    for (const char* ext : {".png", ".exr"}) {
        const fs::path out = dir_ / (std::string("ok") + ext);
        const fs::path records = dir_ / (std::string("loader") + ext);
        fs::create_directories(records);
        // One record per process (the shell popen starts, and the program), in `records`.
        setenv("LD_DEBUG", "files", 1);
        setenv("LD_DEBUG_OUTPUT", (records / "ld").c_str(), 1);
        const CommandRun r = run("render " + scene.string() + " --width 32 --height 24 --out " + out.string());
        unsetenv("LD_DEBUG");
        unsetenv("LD_DEBUG_OUTPUT");
        EXPECT_EQ(r.exitCode, 0) << r.output;
        std::string record;
        for (const auto& file : fs::directory_iterator(records)) {
            std::ifstream in(file.path());
            record.append(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        }
        EXPECT_NE(record.find(std::string("initialize program: ") + CUBERILLE_BINARY), std::string::npos)
            << "no loader record of the program";
        const bool loaded = record.find("libOpenImageIO.so") != std::string::npos;
        EXPECT_EQ(loaded, std::string(ext) == ".exr") << ext;
        EXPECT_TRUE(fs::exists(out)) << ext;
    }
}

// The summary's times add up: the total is the frame plus the resolve, the frame its stages
// plus the rest, each to the printed rounding (0.05 ms a term).
TEST_F(Cli, TheSummaryTimesAddUp) {
    for (const char* scene : {"demo", "fill"}) {
        const CommandRun r = run(std::string("render ") + scene + " --width 320 --height 180 --out " + (dir_ / "s.png").string());
        ASSERT_EQ(r.exitCode, 0) << r.output;
        double total, frame, vertex, front, back, other, resolve;
        const size_t at = r.output.find(" ms = frame ");
        ASSERT_NE(at, std::string::npos) << r.output;
        const size_t start = r.output.rfind(' ', at - 1) + 1;
        ASSERT_EQ(std::sscanf(r.output.c_str() + start,
                              "%lf ms = frame %lf (vertex %lf, front end %lf, back end %lf, other %lf) + resolve %lf",
                              &total, &frame, &vertex, &front, &back, &other, &resolve), 7)
            << r.output;
        EXPECT_NEAR(total, frame + resolve, 0.1 + 1e-9) << r.output;
        EXPECT_NEAR(frame, vertex + front + back + other, 0.25 + 1e-9) << r.output;
        EXPECT_GT(back, 0.0) << r.output;
    }
}

// A voxel model's summary counts what its frame drew: faces (two triangles each) and source
// triangles, which together are the triangles that entered the pipeline.
TEST_F(Cli, AVoxelModelsSummaryCountsTheFacesAndTrianglesItDrew) {
    std::string raw(16 * 16 * 16, '\0');
    for (int z = 4; z < 12; ++z)
        for (int y = 4; y < 12; ++y)
            for (int x = 4; x < 12; ++x) raw[(z * 16 + y) * 16 + x] = char(200);
    std::ofstream(dir_ / "cube.raw", std::ios::binary) << raw;
    const fs::path cvox = dir_ / "cube.cvox";
    ASSERT_EQ(run("isosurface " + (dir_ / "cube.raw").string() + " --dims 16 16 16 --type u8 --iso 100 -o " + cvox.string()).exitCode, 0);
    const CommandRun r = run("render " + cvox.string() + " --width 160 --height 120 --out " + (dir_ / "c.png").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    unsigned long long faces = 0, sources = 0, in = 0;
    const size_t at = r.output.find(" voxel faces and ");
    ASSERT_NE(at, std::string::npos) << r.output;
    ASSERT_EQ(std::sscanf(r.output.c_str() + r.output.rfind(' ', at - 1) + 1,
                          "%llu voxel faces and %llu source triangles drawn, %llu triangles in", &faces, &sources, &in), 3)
        << r.output;
    EXPECT_GT(faces, 0u);
    EXPECT_EQ(in, 2 * faces + sources) << r.output;
}

// A square of two triangles, facing +z, framed by the default camera with room around it.
const char* kSquarePly =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
    "-1 -1 0\n1 -1 0\n1 1 0\n-1 1 0\n3 0 1 2\n3 0 2 3\n";

// A transparent --background: alpha is each pixel's covered fraction (1, 0 and the 4-sample
// steps between on the edges), EXR keeps premultiplied colour (the same bits as over opaque
// black), and PNG stores straight colour beside its alpha.
TEST_F(Cli, ATransparentBackgroundWritesCoverageAsAlpha) {
    const fs::path ply = write("square.ply", kSquarePly);
    const std::string common = "render " + ply.string() + " --width 96 --height 64 --msaa 4 --azimuth 10 --elevation 10 ";
    ASSERT_EQ(run(common + "--background 0.5,0.5,0.5,0 --out " + (dir_ / "clear.exr").string()).exitCode, 0);
    ASSERT_EQ(run(common + "--background 0.5,0.5,0.5,0 --out " + (dir_ / "clear.png").string()).exitCode, 0);
    ASSERT_EQ(run(common + "--background 0,0,0 --out " + (dir_ / "black.exr").string()).exitCode, 0);
    ASSERT_EQ(run(common + "--background 0,0,0 --out " + (dir_ / "black.png").string()).exitCode, 0);
    const auto clear = cuberille::apps::readImage(dir_ / "clear.exr"), black = cuberille::apps::readImage(dir_ / "black.exr");
    const auto clearPng = cuberille::apps::readImage(dir_ / "clear.png"), blackPng = cuberille::apps::readImage(dir_ / "black.png");
    ASSERT_EQ(clear.rgba.size(), black.rgba.size());
    int inside = 0, outside = 0, edge = 0;
    for (size_t i = 0; i < clear.rgba.size() / 4; ++i) {
        const float a = clear.rgba[i * 4 + 3];
        EXPECT_TRUE(a == 0.0f || a == 0.25f || a == 0.5f || a == 0.75f || a == 1.0f) << a;
        (a == 1.0f ? inside : a == 0.0f ? outside : edge)++;
        for (int c = 0; c < 3; ++c) EXPECT_EQ(clear.rgba[i * 4 + c], black.rgba[i * 4 + c]) << i;
        EXPECT_EQ(black.rgba[i * 4 + 3], 1.0f);
        EXPECT_EQ(clearPng.rgba[i * 4 + 3], std::round(a * 255.0f) / 255.0f) << i;
        if (a == 1.0f) {
            for (int c = 0; c < 3; ++c) EXPECT_EQ(clearPng.rgba[i * 4 + c], blackPng.rgba[i * 4 + c]) << i;
        }
    }
    EXPECT_GT(inside, 100);
    EXPECT_GT(outside, 100);
    EXPECT_GT(edge, 10);
}

// --zoom F magnifies F times: the square covers F² times the pixels (to within the edge pixels'
// share), for the framing camera and a placed one alike.
// `batch`: each job's image is the one `render` writes for the same options (bytes compared),
// a scene named by several jobs is loaded once, and failing jobs are reported by line while the
// others still run; the exit code says that some failed.
TEST_F(Cli, BatchRendersEachJobAsRenderDoesAndReportsFailuresByLine) {
    const fs::path gltf = dir_ / "slide.gltf";
    cuberille::testing::writeSlidingCubeGltf(gltf);
    const fs::path tri = write("t.tri", "10 10 100 20 30 90 1 0.2 0.2\n");
    const std::vector<std::pair<std::string, std::string>> good = {
        {"{\"scene\": \"" + gltf.string() + "\", \"out\": \"" + (dir_ / "a.png").string() +
             "\", \"width\": 96, \"height\": 64, \"msaa\": 4, \"time\": 0.25, \"shadows\": \"hybrid\"}",
         gltf.string() + " --width 96 --height 64 --msaa 4 --time 0.25 --shadows hybrid"},
        {"{\"scene\": \"" + gltf.string() + "\", \"out\": \"" + (dir_ / "b.png").string() +
             "\", \"width\": 96, \"height\": 64, \"time\": 0.75, \"frustum_cull\": true, \"eye\": [0, 3, 9]}",
         gltf.string() + " --width 96 --height 64 --time 0.75 --frustum-cull --eye 0,3,9"},
        {"{\"scene\": \"" + tri.string() + "\", \"out\": \"" + (dir_ / "c.png").string() + "\", \"width\": 128, \"height\": 128}",
         tri.string() + " --width 128 --height 128"},
        // false turns a flag off even where it is on by default (the legend)
        {"{\"scene\": \"" + gltf.string() + "\", \"out\": \"" + (dir_ / "e.png").string() +
             "\", \"width\": 320, \"height\": 180, \"view\": \"tiles\", \"legend\": false, \"frustum-cull\": false}",
         gltf.string() + " --width 320 --height 180 --view tiles --no-legend"},
    };
    std::string jobs = "# three good jobs and two bad ones\n" + good[0].first + "\n" + good[1].first + "\n" +
                       "{\"scene\": \"" + gltf.string() + "\", \"out\": \"" + (dir_ / "d.png").string() + "\", \"view\": \"sideways\"}\n" +
                       good[2].first + "\n{\"scene\": \"" + tri.string() + "\", \"colour\": \"red\"}\n" + good[3].first + "\n";
    const fs::path file = write("jobs.jsonl", jobs);
    const CommandRun batch = run("batch " + file.string());
    EXPECT_EQ(batch.exitCode, 1) << batch.output;
    EXPECT_NE(batch.output.find("jobs.jsonl:4: --view: 'sideways' is not"), std::string::npos) << batch.output;
    EXPECT_NE(batch.output.find("jobs.jsonl:6: \"colour\": render has no option --colour"), std::string::npos) << batch.output;
    EXPECT_NE(batch.output.find("6 jobs, 2 failed, 2 scenes loaded"), std::string::npos) << batch.output;
    EXPECT_FALSE(fs::exists(dir_ / "d.png"));
    const char* names[] = {"a.png", "b.png", "c.png", "e.png"};
    for (size_t i = 0; i < good.size(); ++i) {
        const fs::path single = dir_ / ("single-" + std::string(names[i]));
        const CommandRun r = run("render " + good[i].second + " --quiet --out " + single.string());
        ASSERT_EQ(r.exitCode, 0) << r.output;
        std::ifstream a(dir_ / names[i], std::ios::binary), b(single, std::ios::binary);
        const std::string batchBytes((std::istreambuf_iterator<char>(a)), {}), singleBytes((std::istreambuf_iterator<char>(b)), {});
        EXPECT_FALSE(batchBytes.empty()) << names[i];
        EXPECT_EQ(batchBytes, singleBytes) << names[i];
    }
    EXPECT_EQ(run("batch " + (dir_ / "none.jsonl").string()).exitCode, 2);
}

TEST_F(Cli, ZoomMagnifiesTheViewByItsFactor) {
    const fs::path ply = write("square.ply", kSquarePly);
    auto covered = [&](const std::string& options) {
        const fs::path out = dir_ / "z.exr";
        const CommandRun r = run("render " + ply.string() + " --width 200 --height 200 --msaa 4 --background 0,0,0,0 " +
                                 options + " --out " + out.string());
        EXPECT_EQ(r.exitCode, 0) << r.output;
        const auto image = cuberille::apps::readImage(out);
        double sum = 0;
        for (size_t i = 0; i < image.rgba.size() / 4; ++i) sum += image.rgba[i * 4 + 3];
        return sum;
    };
    for (const std::string& camera : {std::string("--azimuth 0 --elevation 0"), std::string("--eye 0,0,8")}) {
        // 1.4: the framed square (two thirds of the frame's height) still fits.
        const double one = covered(camera), closer = covered(camera + " --zoom 1.4"), half = covered(camera + " --zoom 0.5");
        EXPECT_NEAR(closer / one, 1.96, 0.05) << camera;
        EXPECT_NEAR(half / one, 0.25, 0.02) << camera;
    }
}

// The depth view of a 3D scene: EXR holds each covered pixel's distance along the view axis
// (world units), alpha the coverage; an 8-bit file shows those distances as greys spread over
// the codes from kNearestGrey to kFarthestGrey, black where nothing was drawn.
TEST_F(Cli, TheDepthViewIsDistanceInExrAndLegibleInPng) {
    const fs::path ply = write("square.ply", kSquarePly);
    const std::string common = "render " + ply.string() + " --width 640 --height 480 --azimuth 60 --elevation 0 --view depth ";
    ASSERT_EQ(run(common + "--out " + (dir_ / "d.exr").string()).exitCode, 0);
    ASSERT_EQ(run(common + "--out " + (dir_ / "d.png").string()).exitCode, 0);
    const auto exr = cuberille::apps::readImage(dir_ / "d.exr"), png = cuberille::apps::readImage(dir_ / "d.png");
    float nearest = 1e30f, farthest = 0.0f;
    std::set<int> codes;
    for (size_t i = 0; i < exr.rgba.size() / 4; ++i) {
        if (exr.rgba[i * 4 + 3] == 0.0f) {
            EXPECT_EQ(png.rgba[i * 4], 0.0f) << i;  // background black
            continue;
        }
        nearest = std::min(nearest, exr.rgba[i * 4]);
        farthest = std::max(farthest, exr.rgba[i * 4]);
        if (exr.rgba[i * 4 + 3] == 1.0f) codes.insert(int(std::lround(png.rgba[i * 4] * 255.0f)));
    }
    // The square (side 2) seen at 60 degrees: its near and far edges lie 2 sin 60° apart along the view.
    EXPECT_NEAR(farthest - nearest, 2.0f * std::sin(glm::radians(60.0f)), 0.05f);  // to within a pixel at each edge
    EXPECT_EQ(*codes.rbegin(), 255);
    EXPECT_NEAR(*codes.begin(), cuberille::apps::kFarthestGrey * 255.0, 3.0);
    EXPECT_GT(codes.size(), 100u) << "an 8-bit depth view should use the codes between";
}

// A 16-bit PNG holds what the 8-bit one rounds: each channel within half an 8-bit step (plus
// half a 16-bit one) of the 8-bit file's.
TEST_F(Cli, SixteenBitPngsKeepWhatEightBitsRound) {
    const fs::path ply = write("square.ply", kSquarePly);
    const std::string common = "render " + ply.string() + " --width 96 --height 64 --msaa 4 --background 0.2,0.4,0.8 ";
    ASSERT_EQ(run(common + "--png-bits 16 --out " + (dir_ / "wide.png").string()).exitCode, 0);
    ASSERT_EQ(run(common + "--out " + (dir_ / "narrow.png").string()).exitCode, 0);
    const auto wide = cuberille::apps::readImage(dir_ / "wide.png"), narrow = cuberille::apps::readImage(dir_ / "narrow.png");
    ASSERT_EQ(wide.rgba.size(), narrow.rgba.size());
    size_t between = 0;
    for (size_t i = 0; i < wide.rgba.size(); ++i) {
        EXPECT_LE(std::abs(wide.rgba[i] * 255.0f - narrow.rgba[i] * 255.0f), 0.5f + 255.0f / 65535.0f) << i;
        between += std::abs(wide.rgba[i] * 255.0f - std::round(wide.rgba[i] * 255.0f)) > 0.01f;
    }
    EXPECT_GT(between, 0u) << "no value between two 8-bit steps: the file is not 16-bit";
}

// JPEG (through the OpenImageIO module): the PNG's image within JPEG's loss at quality 92.
TEST_F(Cli, JpegOutputIsThePngsImageWithinItsCompression) {
    const fs::path ply = write("square.ply", kSquarePly);
    const std::string common = "render " + ply.string() + " --width 96 --height 64 --msaa 4 ";
    ASSERT_EQ(run(common + "--out " + (dir_ / "a.jpg").string()).exitCode, 0);
    ASSERT_EQ(run(common + "--out " + (dir_ / "a.png").string()).exitCode, 0);
    const auto jpeg = cuberille::apps::readImage(dir_ / "a.jpg"), png = cuberille::apps::readImage(dir_ / "a.png");
    ASSERT_EQ(jpeg.rgba.size(), png.rgba.size());
    double sum = 0;
    for (size_t i = 0; i < png.rgba.size(); ++i) sum += std::abs(jpeg.rgba[i] - png.rgba[i]);
    EXPECT_LT(sum / double(png.rgba.size()), 0.01);  // measured 0.002-0.004
}

// Options the output or the scene cannot honour (a PLY has no animations) are refused.
TEST_F(Cli, OutputOptionsAFileCannotHoldAreRefusedBeforeAnyWork) {
    const fs::path ply = write("square.ply", kSquarePly);
    for (const std::string& options : {std::string("--background 1,1,1,0 --out ") + (dir_ / "x.jpg").string(),
                                       std::string("--png-bits 12 --out ") + (dir_ / "x.png").string(),
                                       std::string("--png-bits 16 --out ") + (dir_ / "x.exr").string(),
                                       std::string("--background 2,0,0 --out ") + (dir_ / "x.png").string(),
                                       std::string("--background 1,1 --out ") + (dir_ / "x.png").string(),
                                       std::string("--animation 0 --out ") + (dir_ / "x.png").string(),
                                       std::string("--zoom 0 --out ") + (dir_ / "x.png").string()}) {
        const CommandRun r = run("render " + ply.string() + " --width 32 --height 32 " + options);
        EXPECT_EQ(r.exitCode, 2) << options << "\n" << r.output;
    }
    for (const char* name : {"x.jpg", "x.png", "x.exr"}) EXPECT_FALSE(fs::exists(dir_ / name)) << name;
}

TEST_F(Cli, MalformedTriGivesExitTwoWithFileAndLineAndWritesNothing) {
    const fs::path scene = write("bad.tri", "1 1 30 2 5 20 1\n1 2 3\n");
    const fs::path out = dir_ / "bad.exr";
    const CommandRun r = run("render " + scene.string() + " --width 32 --height 24 --out " + out.string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find(scene.string() + ":2:"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
    for (const auto& e : fs::directory_iterator(dir_))
        EXPECT_EQ(e.path().extension(), ".tri") << "stray file " << e.path();
}

TEST_F(Cli, FailedRunLeavesEarlierOutputUntouched) {
    const fs::path out = dir_ / "keep.png";
    write("keep.png", "earlier good output");
    const fs::path scene = write("bad.tri", "oops\n");
    EXPECT_EQ(run("render " + scene.string() + " --out " + out.string()).exitCode, 2);
    std::ifstream in(out);
    std::string content((std::istreambuf_iterator<char>(in)), {});
    EXPECT_EQ(content, "earlier good output");
}

TEST_F(Cli, BadUsageGivesExitTwo) {
    EXPECT_EQ(run("render demo --msaa 3 --out " + (dir_ / "x.png").string()).exitCode, 2);
    EXPECT_EQ(run("render demo --out " + (dir_ / "x.tga").string()).exitCode, 2);
    EXPECT_EQ(run("render demo").exitCode, 2);
    EXPECT_EQ(run("render " + (dir_ / "missing.tri").string() + " --out " + (dir_ / "x.png").string()).exitCode, 2);
    EXPECT_EQ(run("frobnicate").exitCode, 2);
}

TEST_F(Cli, RendersMeshFilesAndRejectsBrokenOnes) {
    const fs::path ply = write("tri.ply",
                               "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                               "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    const fs::path obj = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    for (const fs::path& scene : {ply, obj}) {
        const CommandRun r = run("render " + scene.string() + " --width 32 --height 24 --azimuth 0 --elevation 0 --out " +
                                 (dir_ / "m.png").string());
        EXPECT_EQ(r.exitCode, 0) << r.output;
    }
    const fs::path cut = write("cut.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
                                          "property float y\nproperty float z\nend_header\n\x01\x02");
    const CommandRun r = run("render " + cut.string() + " --out " + (dir_ / "cut.png").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find(cut.string() + ": "), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "cut.png"));
    EXPECT_EQ(run("render " + write("x.stl", "solid").string() + " --out " + (dir_ / "x.png").string()).exitCode, 2);
}

// A .glb: 12-byte header, a JSON chunk (space-padded) and, when given, a BIN chunk.
std::string glbWithJson(std::string json, const std::string& bin = "") {
    while (json.size() % 4) json += ' ';
    auto u32 = [](uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); };
    const std::string binChunk = bin.empty() ? "" : u32(uint32_t(bin.size())) + std::string("BIN\0", 4) + bin;
    return "glTF" + u32(2) + u32(uint32_t(12 + 8 + json.size() + binChunk.size())) + u32(uint32_t(json.size())) + "JSON" +
           json + binChunk;
}

// A one-triangle .glb.
std::string triangleGlb() {
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    return glbWithJson(R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
                       R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
                       R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],)"
                       R"("bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"byteLength":36}]})",
                       std::string(reinterpret_cast<const char*>(p), sizeof p));
}

TEST_F(Cli, TruncatedAndCorruptedModelsGiveExitTwoNamingTheFileAndWriteNothing) {
    const std::string glb = triangleGlb();
    const std::string gltf = R"({"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)"
                             R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}],)"
                             R"("bufferViews":[{"buffer":0,"byteLength":36}],)"
                             R"("buffers":[{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}]})";
    ASSERT_EQ(run("render " + write("good.glb", glb).string() + " --width 16 --height 16 --out " + (dir_ / "good.png").string()).exitCode, 0);
    ASSERT_EQ(run("render " + write("good.gltf", gltf).string() + " --width 16 --height 16 --out " + (dir_ / "good.png").string()).exitCode, 0);
    std::string badMagic = glb, longChunk = glb, longBin = glb, shortBuffer = gltf;
    badMagic[0] = 'X';
    longChunk[12] = '\x7f';  // the JSON chunk claims more bytes than the file has
    // The BIN chunk claims 4 bytes past the end while the header's length is the file's, and the
    // buffer one byte more than the file holds (what fuzz_gltf found tinygltf reading past its copy).
    uint32_t jsonLength;
    std::memcpy(&jsonLength, glb.data() + 12, 4);
    longBin[20 + jsonLength] += 4;
    const std::string buffer36 = "\"buffers\":[{\"byteLength\":36}";
    longBin.replace(longBin.find(buffer36), buffer36.size(), "\"buffers\":[{\"byteLength\":37}");
    shortBuffer.replace(shortBuffer.find("\"count\":3"), 9, "\"count\":30");
    const std::vector<std::pair<std::string, std::string>> broken = {
        {"cut-header.glb", glb.substr(0, 10)},
        {"cut-json.glb", glb.substr(0, 40)},
        {"cut-bin.glb", glb.substr(0, glb.size() - 7)},
        {"bad-magic.glb", badMagic},
        {"long-chunk.glb", longChunk},
        {"long-bin.glb", longBin},
        {"cut.gltf", gltf.substr(0, gltf.size() / 2)},
        {"accessor-past-buffer.gltf", shortBuffer},
        {"not-json.gltf", "\x89PNG\r\n"},
        {"index-out-of-range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n"},
        {"garbage.obj", "v 0 0 0\nv 1 0 zero\nf 1 2 3\n"},
        {"cut-ascii.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                          "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0"},
    };
    for (const auto& [name, bytes] : broken) {
        const fs::path file = write(name, bytes);
        const fs::path out = dir_ / (name + ".png");
        const CommandRun r = run("render " + file.string() + " --width 16 --height 16 --out " + out.string());
        EXPECT_EQ(r.exitCode, 2) << name << ": " << r.output;
        // "FILE: problem" or, for line-based formats, "FILE:LINE: problem".
        EXPECT_NE(r.output.find(file.string() + ":"), std::string::npos) << name << ": " << r.output;
        EXPECT_FALSE(fs::exists(out)) << name;
    }
    const CommandRun r = run("render " + (dir_ / "long-bin.glb").string() + " --out " + (dir_ / "long-bin.png").string());
    EXPECT_NE(r.output.find("GLB chunk 1 at byte " + std::to_string(20 + jsonLength) + ": claims 40 bytes, but 36 remain"),
              std::string::npos)
        << r.output;
}

TEST_F(Cli, TurntableWritesNumberedFramesThatDiffer) {
    const fs::path obj = write("wedge.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n");
    const CommandRun r = run("render " + obj.string() + " --turntable 3 --width 32 --height 24 --out " +
                             (dir_ / "t.exr").string() + " --stats " + (dir_ / "t.json").string());
    ASSERT_EQ(r.exitCode, 0) << r.output;
    std::vector<std::string> contents;
    for (const char* name : {"t_000.exr", "t_001.exr", "t_002.exr"}) {
        ASSERT_TRUE(fs::exists(dir_ / name)) << name;
        std::ifstream in(dir_ / name, std::ios::binary);
        contents.emplace_back((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    }
    EXPECT_NE(contents[0], contents[1]) << "frames must show the model from different sides";
    EXPECT_FALSE(fs::exists(dir_ / "t_003.exr"));
    // One summary for the sequence, not one per frame; no progress line when not on a terminal.
    EXPECT_NE(r.output.find("wrote " + (dir_ / "t_000.exr").string() + " .. " + (dir_ / "t_002.exr").string() + " (3 frames"),
              std::string::npos) << r.output;
    size_t wrote = 0;
    for (size_t at = r.output.find("wrote "); at != std::string::npos; at = r.output.find("wrote ", at + 1)) ++wrote;
    EXPECT_EQ(wrote, 1u) << r.output;
    EXPECT_EQ(r.output.find('\r'), std::string::npos) << "a progress line in captured output";
    std::ifstream statsFile(dir_ / "t.json");
    EXPECT_EQ(nlohmann::json::parse(statsFile)["frames"].size(), 3u);
    EXPECT_EQ(run("render " + write("flat.tri", "0 0 1 0 0 1 1\n").string() + " --turntable 2 --out " +
                  (dir_ / "f.png").string()).exitCode, 2);
}

TEST_F(Cli, ShadowModesRenderAndReportWhatTheyTraced) {
    // A box floating over a floor, lit from above: every mode renders; none traces nothing, the
    // map traces nothing, hybrid traces some receivers and raytraced all of them.
    const fs::path obj = write("box.obj",
                               "v -4 0 -4\nv 4 0 -4\nv 4 0 4\nv -4 0 4\n"
                               "v -1 1 -1\nv 1 1 -1\nv 1 1 1\nv -1 1 1\nv -1 2 -1\nv 1 2 -1\nv 1 2 1\nv -1 2 1\n"
                               "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 9 11 10\nf 9 12 11\n"
                               "f 5 10 6\nf 5 9 10\nf 6 11 7\nf 6 10 11\nf 7 12 8\nf 7 11 12\nf 8 9 5\nf 8 12 9\n");
    std::map<std::string, nlohmann::json> stats;
    std::map<std::string, std::string> images;
    for (const std::string mode : {"none", "map", "hybrid", "raytraced"}) {
        const fs::path out = dir_ / (mode + ".png"), json = dir_ / (mode + ".json");
        const CommandRun r = run("render " + obj.string() + " --width 96 --height 64 --shadows " + mode +
                                 " --shadow-map-size 256 --out " + out.string() + " --stats " + json.string());
        ASSERT_EQ(r.exitCode, 0) << mode << ": " << r.output;
        stats[mode] = nlohmann::json::parse(std::ifstream(json));
        std::ifstream in(out, std::ios::binary);
        images[mode] = std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    }
    EXPECT_FALSE(stats["none"].contains("shadows")) << "no shadow stage without --shadows";
    EXPECT_EQ(stats["map"]["shadows"]["raysTraced"], 0);
    const uint64_t receivers = stats["raytraced"]["shadows"]["receiverPixels"];
    EXPECT_GT(receivers, 300u);
    EXPECT_EQ(stats["raytraced"]["shadows"]["raysTraced"], receivers);
    EXPECT_GT(stats["hybrid"]["shadows"]["raysTraced"], 0);
    EXPECT_LT(stats["hybrid"]["shadows"]["raysTraced"], receivers / 2);
    EXPECT_NE(images["none"], images["raytraced"]) << "the box casts a shadow";
    EXPECT_EQ(images["hybrid"], images["raytraced"]);

    // The traced pixels, and the soft variant.
    EXPECT_EQ(run("render " + obj.string() + " --width 96 --height 64 --shadows hybrid --view shadow-pixels --soft "
                  "--soft-samples 2 --out " + (dir_ / "pixels.png").string()).exitCode, 0);
    EXPECT_TRUE(fs::exists(dir_ / "pixels.png"));
}

// Each (arguments, message) pair: exit code 2, the message printed, nothing written to `out`.
void expectRefusedWithoutOutput(std::span<const std::pair<std::string, std::string>> cases, const fs::path& out) {
    for (const auto& [args, message] : cases) {
        const CommandRun r = run(args + " --out " + out.string());
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.output;
        EXPECT_NE(r.output.find(message), std::string::npos) << args << "\n" << r.output;
        EXPECT_FALSE(fs::exists(out)) << args;
    }
}

TEST_F(Cli, ShadowOptionsAreCheckedWithExitTwoAndNothingWritten) {
    const fs::path obj = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const fs::path tri = write("flat.tri", "0 0 1 0 0 1 1\n");
    const fs::path out = dir_ / "o.png";
    const std::pair<std::string, std::string> cases[] = {
        {"render " + obj.string() + " --shadows soft", "--shadows"},
        {"render " + obj.string() + " --shadows map --shadow-map-size 8", "--shadow-map-size"},
        {"render " + obj.string() + " --shadows map --soft-samples 0", "--soft-samples"},
        {"render " + obj.string() + " --shadows map --light-radius -1", "--light-radius"},
        {"render " + obj.string() + " --view shadow-pixels", "--view shadow-pixels"},
        {"render " + tri.string() + " --shadows hybrid", "--shadows"},
        {"render " + obj.string() + " --ao -1", "--ao"},
        {"render " + obj.string() + " --ao 4 --ao-distance -1", "--ao-distance"},
        {"render " + tri.string() + " --ao 4", "--ao: only for 3D scenes"},
    };
    expectRefusedWithoutOutput(cases, out);
}

// --environment: the built-in studio, and an OpenEXR map read through the program's OpenImageIO
// module (the library reads .hdr itself); a map that cannot be used is exit 2 naming it.
TEST_F(Cli, EnvironmentsLightTheModelFromTheStudioOrAnExrAndBadOnesGiveExitTwo) {
    const fs::path obj = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const fs::path exr = dir_ / "sky.exr", out = dir_ / "o.png", json = dir_ / "s.json";
    cuberille::raster::Image sky{64, 32, {}};
    sky.rgba.assign(size_t(64 * 32 * 4), 0.5f);
    cuberille::apps::writeImageAtomically(exr, sky);
    for (const std::string& environment : {std::string("neutral"), exr.string()}) {
        const CommandRun r = run("render " + obj.string() + " --width 48 --height 32 --environment " + environment +
                                 " --out " + out.string() + " --stats " + json.string());
        ASSERT_EQ(r.exitCode, 0) << environment << ": " << r.output;
        const nlohmann::json stats = nlohmann::json::parse(std::ifstream(json));
        EXPECT_GT(stats["stages"]["shade"]["environmentPixels"].get<uint64_t>(), 0u) << environment;
        EXPECT_EQ(stats["stages"]["shade"]["environmentPixels"], stats["stages"]["shade"]["pixelsShaded"]) << environment;
        fs::remove(out);
    }
    const std::pair<std::string, std::string> cases[] = {
        {"render " + obj.string() + " --environment " + (dir_ / "none.hdr").string(), (dir_ / "none.hdr").string()},
        {"render " + obj.string() + " --environment neutral --environment-intensity -2", "--environment-intensity"},
        {"render " + write("flat.tri", "0 0 1 0 0 1 1\n").string() + " --environment neutral", "--environment: only for 3D scenes"},
    };
    expectRefusedWithoutOutput(cases, out);
}

TEST_F(Cli, AccuracyKnobsAreCheckedWithExitTwoAndNothingWritten) {
    const fs::path obj = write("tri.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    const fs::path out = dir_ / "o.png";
    const std::pair<std::string, std::string> cases[] = {
        {"render " + obj.string() + " --supersample 17", "--supersample: must be 1 to 16"},
        {"render " + obj.string() + " --supersample 0", "--supersample: must be 1 to 16"},
        {"render " + obj.string() + " --supersample 16 --width 2000", "exceeds 16384 pixels a side"},
        {"render " + obj.string() + " --supersample 2 --view depth", "--supersample: only with --view color"},
        {"render " + obj.string() + " --texture-filter anisotropic", "--texture-filter: 'anisotropic'"},
        {"render " + obj.string() + " --depth inverted", "--depth: 'inverted' is not standard or reversed"},
    };
    expectRefusedWithoutOutput(cases, out);
}

// N x N supersampling is the box filter over N² grid samples: a pixel an edge halves at x = 10.5
// resolves to exactly half (N even puts N/2 columns of samples on each side), whole pixels to the
// value or to nothing, and the .tri coordinates scale with the frame.
TEST_F(Cli, SupersamplingAveragesAGridOfSamplesPerPixel) {
    const fs::path tri = write("box.tri", "2 2 10.5 2 10.5 6 0.8\n2 2 10.5 6 2 6 0.8\n");
    const fs::path out = dir_ / "s.exr";
    for (int n : {2, 4, 16}) {
        const CommandRun r = run("render " + tri.string() + " --width 16 --height 8 --supersample " +
                                 std::to_string(n) + " --out " + out.string());
        ASSERT_EQ(r.exitCode, 0) << r.output;
        const cuberille::raster::Image im = cuberille::apps::readImage(out);
        ASSERT_EQ(im.width, 16);
        EXPECT_EQ(im.pixel(5, 4)[0], 0.8f) << n;         // inside
        EXPECT_EQ(im.pixel(10, 4)[0], 0.4f) << n;        // halved by the edge at x = 10.5
        EXPECT_EQ(im.pixel(12, 4)[0], 0.0f) << n;        // outside
        EXPECT_EQ(im.pixel(5, 6)[0], 0.0f) << n;         // below the box
    }
}

void writeAnimatedGltf(const fs::path& path) { cuberille::testing::writeSlidingCubeGltf(path); }

std::string fileBytes(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST_F(Cli, AnimatedGltfWithFrustumCullingAndShadowsIsTheSameForAnyThreadCount) {
    const fs::path gltf = dir_ / "slide.gltf";
    writeAnimatedGltf(gltf);
    const std::string common = "render " + gltf.string() + " --camera-index 0 --animate 3 --fps 2 --width 96 --height 64 "
                               "--shadows hybrid --shadow-map-size 256 ";
    for (const auto& [name, extra] : std::vector<std::pair<std::string, std::string>>{
             {"one", "--frustum-cull --threads 1"}, {"two", "--frustum-cull --threads 2"}, {"uncut", "--threads 2"}}) {
        const CommandRun r = run(common + extra + " --out " + (dir_ / (name + ".png")).string() + " --stats " +
                                 (dir_ / (name + ".json")).string());
        ASSERT_EQ(r.exitCode, 0) << r.output;
    }
    for (const char* frame : {"_000.png", "_001.png", "_002.png"}) {
        const std::string one = fileBytes(dir_ / (std::string("one") + frame));
        ASSERT_FALSE(one.empty()) << frame;
        EXPECT_EQ(one, fileBytes(dir_ / (std::string("two") + frame))) << frame << ": thread count changed the image";
        EXPECT_EQ(one, fileBytes(dir_ / (std::string("uncut") + frame))) << frame << ": culling changed the image";
    }
    EXPECT_NE(fileBytes(dir_ / "one_000.png"), fileBytes(dir_ / "one_002.png")) << "the cube moves";
    const nlohmann::json stats = nlohmann::json::parse(std::ifstream(dir_ / "one.json"));
    ASSERT_EQ(stats["frames"].size(), 3u);
    const nlohmann::json& first = stats["frames"][0]["frustumCull"];
    EXPECT_LT(first["trianglesKept"].get<uint64_t>(), first["trianglesIn"].get<uint64_t>() / 2) << "the side row is culled";
    EXPECT_TRUE(first["rebuilt"].get<bool>()) << "built on the first pose";
    EXPECT_FALSE(stats["frames"][1]["frustumCull"]["rebuilt"].get<bool>()) << "refitted to the next";
    EXPECT_GT(stats["frames"][1]["shadows"]["receiverPixels"].get<uint64_t>(), 0u);
    EXPECT_FALSE(stats["frames"][0]["shadows"]["bvhUpdated"].get<bool>()) << "the shadow BVH is built on the first pose";
    EXPECT_TRUE(stats["frames"][1]["shadows"]["bvhUpdated"].get<bool>()) << "and follows the next";
    EXPECT_FALSE(stats["frames"][1]["shadows"]["bvhRebuilt"].get<bool>()) << "a sliding cube is refitted";
    // --animate is for glTF only, and exclusive with --turntable.
    EXPECT_EQ(run("render " + write("t.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").string() + " --animate 2 --out " +
                  (dir_ / "x.png").string()).exitCode, 2);
    EXPECT_EQ(run("render " + gltf.string() + " --animate 2 --turntable 2 --out " + (dir_ / "x.png").string()).exitCode, 2);
}

TEST_F(Cli, AnAnimationsShadowsFromARefittedHierarchyAreThoseOfAFreshOne) {
    // Frame 2 at 2 frames a second is posed at 1 s; rendered alone at --time 1 its shadow stage
    // builds its hierarchy on that pose instead of refitting the first one's.
    const fs::path gltf = dir_ / "slide.gltf";
    writeAnimatedGltf(gltf);
    for (const char* mode : {"hybrid", "raytraced"}) {
        const std::string common = "render " + gltf.string() + " --camera-index 0 --width 96 --height 64 --shadow-map-size 256 --shadows " + mode;
        const std::string name = mode;
        ASSERT_EQ(run(common + " --animate 3 --fps 2 --out " + (dir_ / (name + ".png")).string()).exitCode, 0);
        ASSERT_EQ(run(common + " --time 1 --out " + (dir_ / (name + "_alone.png")).string()).exitCode, 0);
        const std::string animated = fileBytes(dir_ / (name + "_002.png"));
        ASSERT_FALSE(animated.empty());
        EXPECT_EQ(animated, fileBytes(dir_ / (name + "_alone.png"))) << mode;
        // Larsson's lazy update and a rebuild every frame: the same images again.
        for (const char* method : {"lazy", "rebuild"}) {
            const std::string tag = name + "_" + method;
            ASSERT_EQ(run(common + " --frustum-cull --animate 3 --fps 2 --bvh-update " + method + " --stats " +
                          (dir_ / (tag + ".json")).string() + " --out " + (dir_ / (tag + ".png")).string()).exitCode, 0);
            EXPECT_EQ(animated, fileBytes(dir_ / (tag + "_002.png"))) << mode << " " << method;
            const nlohmann::json stats = nlohmann::json::parse(std::ifstream(dir_ / (tag + ".json")));
            EXPECT_EQ(stats["frames"][1]["shadows"]["bvhRebuilt"].get<bool>(), std::string(method) == "rebuild") << method;
            EXPECT_EQ(stats["frames"][1]["frustumCull"]["rebuilt"].get<bool>(), std::string(method) == "rebuild") << method;
        }
        // Wald's grid rebuilt for every pose answers the same rays: the same images again, with
        // ambient occlusion's rays through it too.
        const std::string tag = name + "_grid";
        ASSERT_EQ(run(common + " --animate 3 --fps 2 --accel grid --stats " + (dir_ / (tag + ".json")).string() + " --out " +
                      (dir_ / (tag + ".png")).string()).exitCode, 0);
        EXPECT_EQ(animated, fileBytes(dir_ / (tag + "_002.png"))) << mode << " grid";
        const nlohmann::json stats = nlohmann::json::parse(std::ifstream(dir_ / (tag + ".json")));
        EXPECT_EQ(stats["frames"][1]["shadows"]["accel"].get<std::string>(), "grid");
        EXPECT_TRUE(stats["frames"][1]["shadows"]["bvhRebuilt"].get<bool>()) << "a grid is built again for every pose";
        for (const char* accel : {"bvh", "grid"})
            ASSERT_EQ(run(common + " --ao 4 --animate 3 --fps 2 --accel " + accel + " --out " +
                          (dir_ / (name + "_ao_" + accel + ".png")).string()).exitCode, 0);
        EXPECT_EQ(fileBytes(dir_ / (name + "_ao_grid_002.png")), fileBytes(dir_ / (name + "_ao_bvh_002.png"))) << mode;
        EXPECT_NE(fileBytes(dir_ / (name + "_ao_bvh_002.png")), animated) << "occlusion changed the image";
    }
    EXPECT_EQ(run("render " + gltf.string() + " --animate 2 --bvh-update sometimes --out " + (dir_ / "x.png").string()).exitCode, 2);
    EXPECT_EQ(run("render " + gltf.string() + " --shadows raytraced --accel octree --out " + (dir_ / "x.png").string()).exitCode, 2);
}

// --renderer raytrace over an animation: the camera rays' tree, refitted to each pose (the
// default), lazily updated or rebuilt, and Wald's grid built for each pose all give frame 2 the
// bits of that pose rendered alone; the stats say how the tree followed. Scenes and views the ray
// tracer cannot serve are refused with exit code 2.
TEST_F(Cli, ARayTracedAnimationIsTheSameFromEveryHierarchyAndFromAFreshOne) {
    const fs::path gltf = dir_ / "slide.gltf";
    writeAnimatedGltf(gltf);
    // With shadows on a floor: the shadow rays share the camera rays' tree through every pose.
    const std::string common = "render " + gltf.string() +
                               " --camera-index 0 --width 96 --height 64 --renderer raytrace --msaa 4 --shadows raytraced --ground";
    ASSERT_EQ(run(common + " --time 1 --out " + (dir_ / "alone.png").string()).exitCode, 0);
    const std::string alone = fileBytes(dir_ / "alone.png");
    ASSERT_FALSE(alone.empty());
    for (const char* how : {"bvh refit", "bvh lazy", "bvh rebuild", "grid refit"}) {
        const std::string accel = std::string(how).substr(0, std::string(how).find(' '));
        const std::string method = std::string(how).substr(accel.size() + 1);
        const std::string tag = accel + "_" + method;
        ASSERT_EQ(run(common + " --animate 3 --fps 2 --accel " + accel + " --bvh-update " + method + " --stats " +
                      (dir_ / (tag + ".json")).string() + " --out " + (dir_ / (tag + ".png")).string()).exitCode, 0);
        EXPECT_EQ(fileBytes(dir_ / (tag + "_002.png")), alone) << how;
        const nlohmann::json rays = nlohmann::json::parse(std::ifstream(dir_ / (tag + ".json")))["frames"][1]["primaryRays"];
        EXPECT_EQ(rays["accel"].get<std::string>(), accel) << how;
        EXPECT_EQ(rays["bvhUpdated"].get<bool>(), accel == "bvh") << how;
        EXPECT_EQ(rays["bvhRebuilt"].get<bool>(), method == "rebuild" && accel == "bvh") << how;
        const nlohmann::json shadows = nlohmann::json::parse(std::ifstream(dir_ / (tag + ".json")))["frames"][1]["shadows"];
        EXPECT_EQ(shadows["bvhShared"].get<bool>(), accel == "bvh") << how;
        EXPECT_GT(shadows["raysTraced"].get<uint64_t>(), 0u) << how;
    }
    EXPECT_NE(fileBytes(dir_ / "bvh_refit_000.png"), alone) << "the animation moves";
    const fs::path tri = write("flat.tri", "10 10 100 20 30 90 1 0.2 0.2\n");
    EXPECT_EQ(run("render " + tri.string() + " --renderer raytrace --out " + (dir_ / "x.png").string()).exitCode, 2);
    EXPECT_EQ(run(common + " --view tiles --out " + (dir_ / "x.png").string()).exitCode, 2);
    EXPECT_EQ(run(common + " --renderer path --out " + (dir_ / "x.png").string()).exitCode, 2);
}

TEST_F(Cli, ExplainWritesEveryStageAndRefusesBadInputWithExitTwo) {
    const fs::path out = dir_ / "stages";
    const CommandRun ok = run("explain --triangle \"1.3 1.7 14.6 4.2 5.1 12.8\" --out-dir " + out.string());
    ASSERT_EQ(ok.exitCode, 0) << ok.output;
    for (const char* name : {"1-setup.png", "2-coarse.png", "3-edges.png", "3-edges.csv", "4-coverage-1.png", "4-coverage-16.png",
                             "5-shaded.png", "6-resolve-1.png", "6-resolve-16.png"})
        EXPECT_TRUE(fs::exists(out / name)) << name;
    // The CSV row agrees with the fill rule: a pixel is covered exactly when all three values are >= 0.
    std::ifstream csv(out / "3-edges.csv");
    std::string line;
    std::getline(csv, line);
    int rows = 0;
    while (std::getline(csv, line)) {
        long long x, y, e0, e1, e2;
        int covered;
        ASSERT_EQ(std::sscanf(line.c_str(), "%lld,%lld,%lld,%lld,%lld,%d", &x, &y, &e0, &e1, &e2, &covered), 6) << line;
        EXPECT_EQ(covered, e0 >= 0 && e1 >= 0 && e2 >= 0) << line;
        ++rows;
    }
    EXPECT_GT(rows, 10);
    const fs::path tri = write("two.tri", "1 1 10 2 3 9 0.5\n4 4 12 5 6 11 1\n");
    EXPECT_EQ(run("explain " + tri.string() + " --triangle-index 1 --out-dir " + (dir_ / "two").string()).exitCode, 0);
    const std::pair<std::string, std::string> bad[] = {
        {"explain --out-dir " + (dir_ / "a").string(), "--triangle"},
        {"explain --triangle \"0 0 1 0\" --out-dir " + (dir_ / "b").string(), "--triangle: expected 6 numbers"},
        {"explain --triangle \"0 0 1 0 x 1\" --out-dir " + (dir_ / "b").string(), "--triangle:1"},
        {"explain " + tri.string() + " --triangle-index 2 --out-dir " + (dir_ / "c").string(), "--triangle-index"},
        {"explain --triangle \"0 0 500 0 0 500\" --out-dir " + (dir_ / "d").string(), "at most"},
        {"explain --triangle \"0 0 5 0 0 5\" --scale 2 --out-dir " + (dir_ / "e").string(), "--scale"},
    };
    for (const auto& [args, message] : bad) {
        const CommandRun r = run(args);
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.output;
        EXPECT_NE(r.output.find(message), std::string::npos) << args << "\n" << r.output;
    }
    for (const char* d : {"a", "b", "c", "d", "e"}) EXPECT_FALSE(fs::exists(dir_ / d)) << d;
}

// The subcommands as the tool lists them under "Subcommands:" in its --help: the tests below
// cover every one the tool has, not a list that can fall behind it.
std::vector<std::string> subcommandsOfTheTool() {
    const CommandRun r = run("--help");
    std::vector<std::string> names;
    std::istringstream lines(r.output);
    bool inList = false;
    for (std::string line; std::getline(lines, line);) {
        if (line.rfind("Subcommands:", 0) == 0) {
            inList = true;
            continue;
        }
        if (!inList || line.size() < 3 || line[0] != ' ') continue;
        std::istringstream words(line);
        std::string name;
        words >> name;
        names.push_back(name);
    }
    return names;
}

TEST_F(Cli, HelpOnEveryLevel) {
    EXPECT_EQ(run("--help").exitCode, 0);
    const CommandRun r = run("render --help");
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_NE(r.output.find("--msaa"), std::string::npos);
    const std::vector<std::string> subs = subcommandsOfTheTool();
    EXPECT_GE(subs.size(), 8u) << "render, pack, voxelize, isosurface, info, fly, explain, accuracy at least";
    for (const std::string& sub : subs) {
        const CommandRun help = run(sub + " --help");
        EXPECT_EQ(help.exitCode, 0) << sub;
        EXPECT_NE(help.output.find("Usage: cuberille " + sub), std::string::npos) << sub << ":\n" << help.output;
    }
}

// docs/cli-reference.md is the tool's own --help, every level, so it cannot drift from the tool:
// this test builds it and compares; `make cli-docs` runs it with CUBERILLE_UPDATE_CLI_DOCS=1 to
// write it.
TEST_F(Cli, ReferenceIsTheToolsOwnHelp) {
    std::string doc =
        "# CLI reference\n\nThe output of `cuberille --help` and of each subcommand's `--help`, generated by\n"
        "`make cli-docs` (the test `Cli.ReferenceIsTheToolsOwnHelp` fails when this page and the tool\n"
        "disagree). The options explained with examples are in `docs/cli.md`.\n";
    std::vector<std::string> levels = {""};
    for (const std::string& sub : subcommandsOfTheTool()) levels.push_back(sub);
    for (const std::string& sub : levels) {
        const CommandRun r = run(sub + " --help");
        ASSERT_EQ(r.exitCode, 0) << sub;
        doc += "\n## `cuberille" + (sub.empty() ? std::string() : " " + sub) + "`\n\n```text\n" + r.output + "```\n";
    }
    const fs::path page = fs::path(CUBERILLE_SOURCE_DIR) / "docs" / "cli-reference.md";
    if (getenv("CUBERILLE_UPDATE_CLI_DOCS")) {
        std::ofstream(page) << doc;
        GTEST_SKIP() << "wrote " << page;
    }
    std::ifstream in(page);
    const std::string committed((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    EXPECT_EQ(committed, doc) << page << " differs from the tool's --help: run `make cli-docs`";
}

// A closed tetrahedron as an OBJ.
constexpr const char* kTetrahedronObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

TEST_F(Cli, PackThenVoxelizeMatchesVoxelizingTheMeshAndExportsTheGrid) {
    const fs::path obj = write("tet.obj", kTetrahedronObj);
    const fs::path cgs = dir_ / "tet.cgs";
    CommandRun r = run("pack " + obj.string() + " -o " + cgs.string() + " --chunk-triangles 2");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const fs::path& input : {obj, cgs}) {
        const fs::path out = dir_ / (input.filename().string() + ".cvox"), txt = dir_ / (input.filename().string() + ".txt");
        r = run("voxelize " + input.string() + " --resolution 16 --separability 6 -o " + out.string() +
                " --export-voxels " + txt.string() + " --stats " + (dir_ / "v.json").string());
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_TRUE(fs::exists(out));
        EXPECT_TRUE(fs::exists(dir_ / "v.json"));
    }
    std::ifstream a(dir_ / "tet.obj.txt"), b(dir_ / "tet.cgs.txt");
    const std::string ta((std::istreambuf_iterator<char>(a)), {}), tb((std::istreambuf_iterator<char>(b)), {});
    EXPECT_EQ(ta.rfind("# cuberille voxels 16 0 0 0 1\n", 0), 0u) << ta.substr(0, 80);
    EXPECT_GT(ta.size(), 100u);
    EXPECT_EQ(ta, tb);
}

TEST_F(Cli, VoxelCommandsRejectBadInputWithExitTwoAndWriteNothing) {
    const fs::path obj = write("tet.obj", kTetrahedronObj);
    const fs::path cgs = dir_ / "tet.cgs", out = dir_ / "out.cvox";
    ASSERT_EQ(run("pack " + obj.string() + " -o " + cgs.string()).exitCode, 0);
    // A truncated geometry stream names the file and the chunk.
    std::string bytes;
    {
        std::ifstream in(cgs, std::ios::binary);
        bytes.assign((std::istreambuf_iterator<char>(in)), {});
    }
    const fs::path cut = dir_ / "cut.cgs";
    std::ofstream(cut, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() - 7));
    CommandRun r = run("voxelize " + cut.string() + " -o " + out.string());
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find(cut.string() + ": chunk 0"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out));
    // Bad options.
    ASSERT_EQ(run("voxelize " + obj.string() + " --resolution 8 -o " + out.string()).exitCode, 0);
    EXPECT_EQ(run("voxelize " + obj.string() + " --resolution 12 -o " + (dir_ / "bad.cvox").string()).exitCode, 2);
    EXPECT_EQ(run("voxelize " + obj.string() + " --separability 18 -o " + (dir_ / "bad.cvox").string()).exitCode, 2);
    EXPECT_EQ(run("voxelize " + obj.string() + " -o " + (dir_ / "bad.vox").string()).exitCode, 2);
    EXPECT_FALSE(fs::exists(dir_ / "bad.cvox"));
    // A volume of the wrong size.
    const fs::path raw = write("v.raw", std::string(100, '\x10'));
    r = run("isosurface " + raw.string() + " --dims 5 5 5 --type u8 --iso 8 -o " + (dir_ / "iso.cvox").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("125"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "iso.cvox"));
    r = run("isosurface " + write("w.raw", std::string(125, '\x10')).string() +
            " --dims 5 5 5 --type u8 --iso 8 -o " + (dir_ / "iso.cvox").string());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir_ / "iso.cvox"));
    // `info` reads both formats, and rejects a truncated voxel file naming it.
    r = run("info " + out.string());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("voxel model, 8^3"), std::string::npos) << r.output;
    EXPECT_EQ(run("info " + cgs.string()).exitCode, 0);
    {
        std::ifstream in(out, std::ios::binary);
        bytes.assign((std::istreambuf_iterator<char>(in)), {});
    }
    const fs::path cutVoxels = dir_ / "cut.cvox";
    std::ofstream(cutVoxels, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size() - 5));
    r = run("info " + cutVoxels.string());
    EXPECT_EQ(r.exitCode, 2) << r.output;
    EXPECT_NE(r.output.find(cutVoxels.string() + ": block"), std::string::npos) << r.output;
    // The voxel model renders, also as its LOD view; the lod view is refused for other scenes.
    r = run("render " + out.string() + " --width 64 --height 48 --view lod --out " + (dir_ / "v.png").string() +
            " --stats " + (dir_ / "v.json").string());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(fs::exists(dir_ / "v.png"));
    EXPECT_EQ(run("render " + obj.string() + " --view lod --out " + (dir_ / "w.png").string()).exitCode, 2);
    r = run("render " + out.string() + " --width 64 --height 48 --view visibility --debug-camera --out " +
            (dir_ / "d.png").string());
    EXPECT_EQ(r.exitCode, 0) << r.output;
    // A failed run leaves the earlier good output untouched.
    const auto before = fs::file_size(out);
    EXPECT_EQ(run("voxelize " + cut.string() + " -o " + out.string()).exitCode, 2);
    EXPECT_EQ(fs::file_size(out), before);
}

TEST_F(Cli, FlyRecordsEveryFrameAndSurvivesACorruptBlock) {
    const fs::path obj = write("tet.obj", kTetrahedronObj), model = dir_ / "tet.cvox";
    ASSERT_EQ(run("voxelize " + obj.string() + " --resolution 256 -o " + model.string()).exitCode, 0);
    const fs::path csv = dir_ / "f.csv", plot = dir_ / "f.png", out = dir_ / "frames";
    CommandRun r = run("fly " + model.string() + " --path zoom --frames 6 --width 96 --height 64 --msaa 1 --stats " +
                       csv.string() + " --plot " + plot.string() + " --out-dir " + out.string() +
                       " --save-every 2 --budget-mib 16 --upload-limit 0.05");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("flew 6 frames"), std::string::npos) << r.output;
    std::ifstream in(csv);
    std::string line;
    std::getline(in, line);
    EXPECT_EQ(line.rfind("frame,settling,frame_ms,", 0), 0u) << line;
    int pathRows = 0, settlingRows = 0;
    while (std::getline(in, line)) ++(line.find(",0,") == line.find(',') ? pathRows : settlingRows);
    EXPECT_EQ(pathRows, 6);
    EXPECT_GT(settlingRows, 0) << "the upload limit leaves loading to finish after the path";
    EXPECT_GT(fs::file_size(plot), 1000u);
    for (const char* name : {"frame_00000.png", "frame_00002.png", "frame_00004.png", "final.png"})
        EXPECT_TRUE(fs::exists(out / name)) << name;
    EXPECT_FALSE(fs::exists(out / "frame_00001.png"));
    // A keyframe file.
    const fs::path keys = write("keys.txt", "# from the front, closer\n0.4 0.4 3  0.4 0.4 0.3\n0.4 0.4 1.5  0.4 0.4 0.3\n");
    r = run("fly " + model.string() + " --path " + keys.string() + " --frames 3 --width 64 --height 48 --quiet");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_TRUE(r.output.empty()) << r.output;
    // A corrupt block in the middle of the flight: reported once, the run goes on.
    std::string bytes;
    {
        std::ifstream f(model, std::ios::binary);
        bytes.assign((std::istreambuf_iterator<char>(f)), {});
    }
    uint64_t blocks = 0, offset = 0;
    std::memcpy(&blocks, bytes.data() + 64, 8);
    ASSERT_GT(blocks, 2u);
    std::memcpy(&offset, bytes.data() + 96 + (blocks - 1) * 64 + 24, 8);
    bytes[offset + 3] = char(0xFF);
    const fs::path bad = dir_ / "bad.cvox";
    std::ofstream(bad, std::ios::binary).write(bytes.data(), std::streamsize(bytes.size()));
    r = run("fly " + bad.string() + " --path zoom --frames 4 --width 64 --height 48 --pixel-error 0 --no-occlusion");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    const std::string warning = bad.string() + ": block " + std::to_string(blocks - 1);
    EXPECT_NE(r.output.find(warning), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find(warning), r.output.rfind(warning)) << "reported once: " << r.output;
    EXPECT_NE(r.output.find("1 block could not be read"), std::string::npos) << r.output;
}

TEST_F(Cli, FlyRejectsBadOptionsWithExitTwoAndWritesNothing) {
    const fs::path obj = write("tet.obj", kTetrahedronObj), model = dir_ / "tet.cvox";
    ASSERT_EQ(run("voxelize " + obj.string() + " --resolution 64 -o " + model.string()).exitCode, 0);
    const fs::path csv = dir_ / "f.csv";
    const fs::path oneKey = write("one.txt", "0 0 3 0 0 0\n"), badKey = write("bad.txt", "0 0 3 0 0 0\n1 2 x 0 0 0\n");
    for (const std::string& args :
         {model.string() + " --refine sometimes", model.string() + " --frames 0", obj.string(),
          model.string() + " --path " + (dir_ / "missing.txt").string(), model.string() + " --path " + oneKey.string(),
          model.string() + " --path " + badKey.string(), model.string() + " --save-every 2",
          model.string() + " --msaa 3", model.string() + " --budget-mib 0", model.string() + " --plot p.bmpx",
          (dir_ / "absent.cvox").string()}) {
        const CommandRun r = run("fly " + args + " --stats " + csv.string());
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.output;
        EXPECT_FALSE(fs::exists(csv)) << args;
    }
    const CommandRun r = run("fly " + model.string() + " --path " + badKey.string());
    EXPECT_NE(r.output.find(badKey.string() + ":2: "), std::string::npos) << r.output;
}

}  // namespace

TEST_F(Cli, AccuracyNamesTheSceneItCannotRenderAndTheLimitsItKeeps) {
    const CommandRun missing = run("accuracy " + (dir_ / "missing.tri").string() + " --out " + (dir_ / "r").string());
    EXPECT_EQ(missing.exitCode, 2);
    EXPECT_NE(missing.output.find("missing.tri: cannot open file"), std::string::npos) << missing.output;
    const CommandRun wide = run("accuracy demo --width 5000 --out " + (dir_ / "r").string());
    EXPECT_EQ(wide.exitCode, 2);
    EXPECT_NE(wide.output.find("--width and --height: 8 to 1024 pixels"), std::string::npos) << wide.output;
    EXPECT_FALSE(fs::exists(dir_ / "r" / "report.json"));
}

// The message audit (docs/robustness.md): one malformed input per reader, each refused with exit
// code 2 and a message that starts with the file's name and says where (a line, an element, a
// node, a byte offset) and what is wrong. tinygltf's own parse errors name the file and the
// problem only; that reader is the one place without a position.
TEST_F(Cli, EveryReaderNamesTheFileThePlaceAndTheProblem) {
    const fs::path tet = write("tet.obj", kTetrahedronObj), model = dir_ / "tet.cvox";
    ASSERT_EQ(run("voxelize " + tet.string() + " --resolution 64 -o " + model.string()).exitCode, 0);
    std::string head;
    {
        std::ifstream in(model, std::ios::binary);
        head.assign(100, '\0');
        in.read(head.data(), 100);
    }
    struct Case {
        std::string command, file, place, problem;
    };
    const Case cases[] = {
        {"render " + write("a.tri", "1 1 30 2 5 20 1\n1 2 3 4 5\n").string(), "a.tri", "a.tri:2:", "expected 7 numbers"},
        {"render " + write("b.obj", "v 0 0 0\nv 1 0 zz\nf 1 2 3\n").string(), "b.obj", "b.obj:2:", "not a finite number"},
        {"render " + write("c.obj", "v 0 0 0\nv 1 0 0\nf 1 2 7\n").string(), "c.obj", "c.obj:3:", "out of range"},
        {"render " + write("d.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                    "property float z\nend_header\n0 0 0\n1 0 0\n0 1\n").string(),
         "d.ply", "element 'vertex'", "cannot fit"},
        {"render " + write("e.gltf", R"({"asset":{"version":"2.0"},"nodes":[{"children":[1]},{"children":[0]}],)"
                                     R"("scenes":[{"nodes":[0]}]})").string(),
         "e.gltf", "node 1", "deeper than 256"},
        {"render " + write("f.gltf", R"({"asset":{"version":"2.0"},"meshes":[{"primitives":[{"attributes":)"
                                     R"({"POSITION":5}}]}],"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]})").string(),
         "f.gltf", "mesh 0 primitive 0, accessor 5", "does not exist"},
        {"render " + write("f2.gltf", "{\"asset\": {\"version\": \"2.0\"},\n \"scenes\": [{\"nodes\": [0}]}").string(),
         "f2.gltf", "line 2, column", "unexpected '}'"},
        {"render " + write("f3.glb", glbWithJson("{\"asset\": {\"version\": \"2.0\"},\n \"scenes\": [{\"nodes\": [0}]}")).string(),
         "f3.glb", "JSON chunk (from byte 20): [json.exception.parse_error.101] parse error at line 2, column", "unexpected '}'"},
        {"render " + write("f4.glb", glbWithJson("{}").substr(0, 10)).string(), "f4.glb", "GLB header", "Too short"},
        {"render " + write("g.cvox", head).string(), "g.cvox", "byte 96", "truncated"},
        {"info " + write("h.cvox", head).string(), "h.cvox", "byte 96", "truncated"},
        {"fly " + model.string() + " --path " + write("i.path", "0 0 5 0 0 0\n").string() + " --frames 2",
         "i.path", "i.path", "at least two keyframes"},
        {"isosurface " + write("j.raw", "abc").string() + " --dims 2 2 2 --iso 1", "j.raw", "j.raw", "need 8"},
    };
    for (const Case& c : cases) {
        const fs::path out = dir_ / "out.png";
        const CommandRun r = run(c.command + (c.command.rfind("render", 0) == 0 ? " --out " + out.string() : "") +
                                 (c.command.rfind("fly", 0) == 0 ? " --out-dir " + (dir_ / "fly").string() : "") +
                                 (c.command.rfind("isosurface", 0) == 0 ? " -o " + (dir_ / "iso.cvox").string() : ""));
        EXPECT_EQ(r.exitCode, 2) << c.command << "\n" << r.output;
        const size_t at = r.output.find("cuberille: ");
        ASSERT_NE(at, std::string::npos) << r.output;
        const std::string message = r.output.substr(at + 11);
        EXPECT_NE(message.find(c.file), std::string::npos) << message;
        EXPECT_NE(message.find(c.place), std::string::npos) << "no place in: " << message;
        EXPECT_NE(message.find(c.problem), std::string::npos) << message;
        EXPECT_FALSE(fs::exists(out));
    }
}

// Strip files as scanners write them and the same mesh as a face list: one PLY reader serves
// render and voxelize, so both see the same triangles (the same image bit for bit, the same voxels).
TEST_F(Cli, StripAndFaceListPlyFilesGiveTheSameImageAndTheSameVoxels) {
    using cuberille::testing::PlyConnectivity;
    const cuberille::testing::PlyGrid grid;
    auto renderAndVoxelize = [&](const std::string& name, PlyConnectivity kind, bool binary) {
        const fs::path ply = write(name + ".ply", grid.ply(kind, binary));
        const fs::path image = dir_ / (name + ".exr"), voxels = dir_ / (name + ".cvox");
        CommandRun r = run("render " + ply.string() + " --width 64 --height 48 --msaa 4 --out " + image.string());
        EXPECT_EQ(r.exitCode, 0) << r.output;
        r = run("voxelize " + ply.string() + " --resolution 32 -o " + voxels.string());
        EXPECT_EQ(r.exitCode, 0) << r.output;
        return std::make_pair(cuberille::apps::readImage(image), fileBytes(voxels));
    };
    for (bool binary : {false, true}) {  // ASCII positions are rounded to 6 decimals: compare like with like
        const auto faces = renderAndVoxelize(binary ? "facesb" : "facesa", PlyConnectivity::FaceList, binary);
        ASSERT_FALSE(faces.second.empty());
        for (PlyConnectivity kind : {PlyConnectivity::StripsWithRestarts, PlyConnectivity::StripPerInstance,
                                     PlyConnectivity::StitchedStrip}) {
            const std::string name = "strips" + std::to_string(int(kind)) + (binary ? "b" : "a");
            const auto strips = renderAndVoxelize(name, kind, binary);
            EXPECT_TRUE(strips.first.rgba == faces.first.rgba) << name << ": the images differ";
            EXPECT_TRUE(strips.second == faces.second) << name << ": the voxel files differ";
        }
    }
}

// Every command whose input yields nothing to work on fails with exit code 2, names the file and
// what was missing, and writes no output.
TEST_F(Cli, NoCommandTurnsNothingIntoSuccess) {
    const std::string header = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                               "property float z\n";
    const std::string corners = "0 0 0\n1 0 0\n0 1 0\n";
    const std::vector<fs::path> meshes = {
        write("points.ply", header + "end_header\n" + corners),
        write("nofaces.ply", header + "element face 0\nproperty list uchar int vertex_indices\nend_header\n" + corners),
        write("joins.ply", header + "element tristrips 1\nproperty list int int vertex_indices\nend_header\n" + corners +
                               "4 0 1 1 2\n"),
        write("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
    };
    auto expectRefused = [&](const std::string& args, const fs::path& input, const fs::path& output, const char* missing) {
        const CommandRun r = run(args);
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.output;
        EXPECT_NE(r.output.find(input.string() + ": " + missing), std::string::npos) << args << "\n" << r.output;
        EXPECT_FALSE(fs::exists(output)) << args;
    };
    for (const fs::path& mesh : meshes) {
        const fs::path cgs = dir_ / "x.cgs", cvox = dir_ / "x.cvox", png = dir_ / "x.png";
        expectRefused("pack " + mesh.string() + " -o " + cgs.string(), mesh, cgs, "no triangles");
        expectRefused("voxelize " + mesh.string() + " -o " + cvox.string(), mesh, cvox, "no triangles");
        expectRefused("render " + mesh.string() + " --out " + png.string(), mesh, png, "no triangles");
    }
    const fs::path gltf = dir_ / "lines.gltf";
    {
        cuberille::testing::GltfBuilder b;
        const int mesh = b.push("meshes", {{"primitives", {{{"attributes", {{"POSITION", b.positions({{0, 0, 0}, {1, 0, 0}})}}},
                                                            {"mode", 1}}}}});
        b.json()["scenes"] = {{{"nodes", {b.push("nodes", {{"mesh", mesh}})}}}};
        b.json()["scene"] = 0;
        b.write(gltf);
    }
    expectRefused("render " + gltf.string() + " --out " + (dir_ / "l.png").string(), gltf, dir_ / "l.png", "no triangles");
    expectRefused("voxelize " + gltf.string() + " -o " + (dir_ / "l.cvox").string(), gltf, dir_ / "l.cvox", "no triangles");
    const fs::path tri = write("empty.tri", "# nothing but a comment\n");
    expectRefused("render " + tri.string() + " --out " + (dir_ / "t.exr").string(), tri, dir_ / "t.exr", "no triangles");
    // A volume with nothing at or above the iso value.
    const fs::path raw = write("low.raw", std::string(125, '\x02'));
    expectRefused("isosurface " + raw.string() + " --dims 5 5 5 --type u8 --iso 8 -o " + (dir_ / "i.cvox").string(), raw,
                  dir_ / "i.cvox", "no voxels");
    // A voxel model of no blocks (no command writes one any more; an older file may be one).
    const fs::path empty = dir_ / "empty.cvox";
    {
        cuberille::voxel::VoxelModel model;
        model.grid.resolution = 8;
        model.blockSize = 8;
        std::ofstream out(empty, std::ios::binary);
        cuberille::voxel::writeCvox(model, out);
    }
    expectRefused("render " + empty.string() + " --out " + (dir_ / "e.png").string(), empty, dir_ / "e.png", "no voxels");
    expectRefused("fly " + empty.string() + " --frames 2 --out-dir " + (dir_ / "flight").string(), empty,
                  dir_ / "flight" / "final.png", "no voxels");
}

// One classifier of file kinds serves every command: each input and output extension is
// recognised in upper and mixed case as in lower case (scene/file_names.h).
TEST_F(Cli, EveryCommandTakesEveryFileKindInAnyCase) {
    const std::string ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                            "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
                            "0 0 0\n1 0 0\n1 1 0\n0 1 1\n3 0 1 2\n3 0 2 3\n";
    auto gzip = [&](const fs::path& path, const std::string& bytes) {
        gzFile f = gzopen(path.string().c_str(), "wb");
        gzwrite(f, bytes.data(), unsigned(bytes.size()));
        gzclose(f);
        return path;
    };
    for (const bool upper : {false, true}) {
        const std::string prefix = upper ? "upper" : "mixed";
        auto ext = [&](std::string e) {  // ".ply.gz" -> ".PLY.GZ" or ".Ply.Gz"
            for (size_t i = 0; i < e.size(); ++i)
                if (upper || (i > 0 && e[i - 1] == '.')) e[i] = char(std::toupper(static_cast<unsigned char>(e[i])));
            return e;
        };
        const std::string n = prefix + "-";
        const fs::path tri = write(n + "s" + ext(".tri"), "1 1 30 2 5 20 1\n");
        const fs::path plyFile = write(n + "m" + ext(".ply"), ply);
        const fs::path plyGz = gzip(dir_ / (n + "z" + ext(".ply.gz")), ply);
        const fs::path obj = write(n + "m" + ext(".obj"), kTetrahedronObj);
        const fs::path gltf = dir_ / (n + "slide" + ext(".gltf"));
        cuberille::testing::writeSlidingCubeGltf(gltf);
        const fs::path glb = write(n + "g" + ext(".glb"), triangleGlb());
        const fs::path png = dir_ / (n + "o" + ext(".png")), exr = dir_ / (n + "o" + ext(".exr"));
        const fs::path cgs = dir_ / (n + "s" + ext(".cgs")), cvox = dir_ / (n + "v" + ext(".cvox"));
        const std::vector<std::string> commands = {
            "render " + tri.string() + " --width 32 --height 24 --out " + exr.string(),
            "render " + tri.string() + " --width 32 --height 24 --out " + png.string(),
            "render " + plyFile.string() + " --width 32 --height 24 --out " + png.string(),
            "render " + plyGz.string() + " --width 32 --height 24 --out " + png.string(),
            "render " + obj.string() + " --width 32 --height 24 --out " + png.string(),
            "render " + glb.string() + " --width 32 --height 24 --out " + png.string(),
            "render " + gltf.string() + " --camera-index 0 --animate 2 --width 32 --height 24 --out " + png.string(),
            "render " + obj.string() + " --turntable 2 --width 32 --height 24 --out " + png.string(),
            "pack " + plyGz.string() + " -o " + cgs.string(),
            "info " + cgs.string(),
            "voxelize " + cgs.string() + " --resolution 16 -o " + cvox.string(),
            "voxelize " + gltf.string() + " --resolution 16 -o " + cvox.string(),
            "voxelize " + obj.string() + " --resolution 16 -o " + cvox.string(),
            "info " + cvox.string(),
            "render " + cvox.string() + " --width 32 --height 24 --out " + png.string(),
            "fly " + cvox.string() + " --frames 2 --width 32 --height 24 --out-dir " + (dir_ / (n + "flight")).string(),
            "explain " + tri.string() + " --out-dir " + (dir_ / (n + "stages")).string() + " --quiet",
        };
        for (const std::string& c : commands) {
            const bool quietable = !c.starts_with("explain") && !c.starts_with("info");
            const CommandRun r = run(c + (quietable ? " --quiet" : ""));
            EXPECT_EQ(r.exitCode, 0) << c << "\n" << r.output;
        }
        EXPECT_TRUE(fs::exists(png)) << png;
        EXPECT_TRUE(fs::exists(exr)) << exr;
    }
}

// A mistyped command or option is named with the nearest valid one; a scene that is none lists
// what is; --version answers.
TEST_F(Cli, MessagesNameTheNearestCommandOptionOrScene) {
    CommandRun r = run("--version");
    EXPECT_EQ(r.exitCode, 0);
    EXPECT_EQ(r.output.rfind("cuberille ", 0), 0u) << r.output;
    r = run("frobnicate");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("'frobnicate' is not a command"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("accuracy"), std::string::npos) << "every command listed: " << r.output;
    r = run("rendr demo");
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("did you mean 'render'?"), std::string::npos) << r.output;
    r = run("render demo --msaaa 4 --out " + (dir_ / "x.png").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("unknown option --msaaa; did you mean '--msaa'?"), std::string::npos) << r.output;
    r = run("render dem --out " + (dir_ / "x.png").string());
    EXPECT_EQ(r.exitCode, 2);
    for (const char* named : {".cvox", "demo", "field", "subpixel", "fill"})
        EXPECT_NE(r.output.find(named), std::string::npos) << named << " missing from: " << r.output;
    r = run("explain --triangle \"1 2 3\" --out-dir " + (dir_ / "stages").string());
    EXPECT_EQ(r.exitCode, 2);
    EXPECT_NE(r.output.find("expected 6 numbers (x0 y0 x1 y1 x2 y2), found 3"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir_ / "x.png"));
}

// A run writes all its outputs or none: a path that could only fail at the end (a folder, a
// missing folder) is refused with exit code 2 before any work, and nothing is left behind.
TEST_F(Cli, OutputPathsAreCheckedBeforeAnyWork) {
    fs::create_directories(dir_ / "folder.png");
    const fs::path missing = dir_ / "missing" / "x.png", image = dir_ / "image.png";
    const fs::path obj = write("tet.obj", kTetrahedronObj);
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"render demo --width 32 --height 24 --out " + (dir_ / "folder.png").string(), "is a folder"},
        {"render demo --width 32 --height 24 --out " + missing.string(), "does not exist"},
        {"render demo --width 32 --height 24 --out " + image.string() + " --stats " + (dir_ / "missing" / "s.json").string(),
         "--stats"},
        {"render demo --width 32 --height 24 --turntable 2 --out " + missing.string(), "does not exist"},
        {"pack " + obj.string() + " -o " + (dir_ / "missing" / "t.cgs").string(), "does not exist"},
        {"voxelize " + obj.string() + " -o " + (dir_ / "t.cvox").string() + " --stats " + (dir_ / "folder.png").string(),
         "is a folder"},
        {"fly " + (dir_ / "t.cvox").string() + " --stats " + (dir_ / "missing" / "f.csv").string(), "does not exist"},
    };
    for (const auto& [args, problem] : cases) {
        const CommandRun r = run(args);
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.output;
        EXPECT_NE(r.output.find(problem), std::string::npos) << args << "\n" << r.output;
    }
    EXPECT_FALSE(fs::exists(image)) << "the image was written although --stats could not be";
    EXPECT_FALSE(fs::exists(dir_ / "t.cvox"));
    for (const auto& e : fs::recursive_directory_iterator(dir_))
        EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << "left behind: " << e.path();
}

// An option that would do nothing in its combination is refused rather than ignored.
TEST_F(Cli, OptionsThatWouldDoNothingAreRefused) {
    const fs::path ply = write("tri.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
                                          "property float z\nelement face 1\nproperty list uchar int vertex_indices\n"
                                          "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    const fs::path out = dir_ / "x.png";
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"render demo --turntable 0 --out " + out.string(), "--turntable"},
        {"render " + ply.string() + " --time 1.5 --out " + out.string(), "--time: only glTF"},
        {"render demo --supersample 2 --turntable 2 --out " + out.string(), "--supersample: not with --turntable"},
    };
    for (const auto& [args, problem] : cases) {
        const CommandRun r = run(args);
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.output;
        EXPECT_NE(r.output.find(problem), std::string::npos) << args << "\n" << r.output;
    }
    EXPECT_FALSE(fs::exists(out));
    EXPECT_FALSE(fs::exists(dir_ / "x_000.png"));
}

// A camera the user places: --eye looks at the model (or away from it with --target), and a
// z-up file stands up with --up-axis z.
TEST_F(Cli, APlacedCameraSeesWhatItLooksAtAndZUpFilesStandUp) {
    const fs::path tet = write("tet.obj", kTetrahedronObj);
    auto samplesPassed = [&](const std::string& args) {
        const fs::path stats = dir_ / "s.json";
        const CommandRun r = run("render " + args + " --width 64 --height 48 --out " + (dir_ / "x.png").string() +
                                 " --stats " + stats.string() + " --quiet");
        EXPECT_EQ(r.exitCode, 0) << args << "\n" << r.output;
        std::ifstream in(stats);
        return nlohmann::json::parse(in)["stages"]["depth"]["samplesPassed"].get<uint64_t>();
    };
    EXPECT_GT(samplesPassed(tet.string() + " --eye 0.3,0.3,3"), 100u);
    EXPECT_EQ(samplesPassed(tet.string() + " --eye 0.3,0.3,3 --target 0.3,0.3,10"), 0u) << "looking away";
    EXPECT_GT(samplesPassed(tet.string() + " --eye 3,0.3,0.3 --target 0,0.3,0.3 --up 0,0,1 --fov 20"), 100u);

    // A post 2 long along z, as a z-up scan stores it: seen from the front (azimuth 0, elevation
    // 0), it lies pointing at the camera unless turned up, when it stands tall.
    const fs::path post = write("post.obj", "v -0.1 -0.1 0\nv 0.1 -0.1 0\nv 0.1 0.1 0\nv -0.1 0.1 0\n"
                                            "v -0.1 -0.1 2\nv 0.1 -0.1 2\nv 0.1 0.1 2\nv -0.1 0.1 2\n"
                                            "f 1 3 2\nf 1 4 3\nf 5 6 7\nf 5 7 8\nf 1 2 6\nf 1 6 5\n"
                                            "f 2 3 7\nf 2 7 6\nf 3 4 8\nf 3 8 7\nf 4 1 5\nf 4 5 8\n");
    auto extent = [&](const std::string& extra) {  // covered columns and rows
        const fs::path out = dir_ / "post.exr";
        const CommandRun r = run("render " + post.string() + " --azimuth 0 --elevation 0 --width 64 --height 64 --out " +
                                 out.string() + extra + " --quiet");
        EXPECT_EQ(r.exitCode, 0) << r.output;
        const cuberille::raster::Image im = cuberille::apps::readImage(out);
        int minX = im.width, maxX = -1, minY = im.height, maxY = -1;
        for (int y = 0; y < im.height; ++y)
            for (int x = 0; x < im.width; ++x)
                if (std::abs(im.pixel(x, y)[0] - 0.05f) > 1e-3f)
                    minX = std::min(minX, x), maxX = std::max(maxX, x), minY = std::min(minY, y), maxY = std::max(maxY, y);
        return std::make_pair(maxX - minX + 1, maxY - minY + 1);
    };
    const auto lying = extent(""), standing = extent(" --up-axis z");
    EXPECT_LE(lying.second, lying.first + 2) << "seen end-on: about as tall as wide";
    EXPECT_GT(standing.second, 4 * standing.first) << "stood up: tall and narrow";

    const std::vector<std::string> refused = {
        tet.string() + " --target 0,0,0", tet.string() + " --eye 1,2", tet.string() + " --eye 0,0,3 --target 0,0,3",
        tet.string() + " --up-axis x", write("s.tri", "1 1 9 1 1 9 1\n").string() + " --eye 0,0,3",
        tet.string() + " --eye 0,0,3 --fov 200"};
    for (const std::string& args : refused) {
        const CommandRun r = run("render " + args + " --out " + (dir_ / "r.png").string());
        EXPECT_EQ(r.exitCode, 2) << args << "\n" << r.output;
    }
    EXPECT_FALSE(fs::exists(dir_ / "r.png"));
}
