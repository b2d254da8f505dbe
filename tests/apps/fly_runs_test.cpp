// A flight taken apart into runs of its path's frames (render::FlySettings::firstFrame), as the
// distributed runner flies it: every run numbers its frames as the whole flight does, only the run
// that ends the path settles, the settled image is the whole flight's, and a run's result crosses
// a process boundary as JSON without losing anything the CSV shows.

#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "apps/fly_command.h"
#include "tests/lod/lod_test_support.h"
#include "tests/temp_paths.h"

namespace cuberille {
namespace {

namespace fs = std::filesystem;

apps::FlyOptions sphereFlight(const fs::path& model) {
    apps::FlyOptions o;
    o.model = model;
    o.path = "orbit";
    o.frames = 7;
    o.width = 64, o.height = 48, o.msaa = 1;
    o.quiet = true;
    return o;
}

TEST(FlightRuns, RunsNumberFramesAsOneFlightAndOnlyTheLastSettlesOnTheFlightsImage) {
    const fs::path model = testing::writeTemp("runs.cvox", testing::cvoxBytes(testing::spherePyramid(64, 3)));
    const apps::FlyOptions whole = sphereFlight(model);
    const apps::FlyResult one = apps::runFly(whole);
    ASSERT_TRUE(one.settled);
    std::vector<apps::FlyResult> runs;
    for (const auto& [first, count] : std::vector<std::pair<int, int>>{{0, 3}, {3, 3}, {6, 1}}) {
        apps::FlyOptions o = whole;
        o.firstFrame = first, o.runFrames = count;
        runs.push_back(apps::runFly(o));
        const apps::FlyResult& r = runs.back();
        EXPECT_EQ(r.pathFrames, count);
        for (int i = 0; i < count; ++i) EXPECT_EQ(r.frames[size_t(i)].index, first + i);
        const bool last = first + count == whole.frames;
        // Only the run that ends the path settles (which may take no frame at all, when its last
        // frame already had every block it needed).
        EXPECT_EQ(r.settled, last);
        if (!last) { EXPECT_EQ(r.frames.size(), size_t(count)); }
        if (last) { EXPECT_EQ(r.finalImage.rgba, one.finalImage.rgba) << "the settled image is the whole model's"; }
    }
    std::swap(runs[0], runs[2]);  // joined in path order whatever order they came back in
    const apps::FlyResult joined = apps::joinFlyRuns(runs);
    EXPECT_EQ(joined.pathFrames, whole.frames);
    for (size_t i = 0; i < joined.frames.size(); ++i) EXPECT_EQ(joined.frames[i].index, int(i));
    EXPECT_EQ(joined.settled, one.settled);
    EXPECT_EQ(joined.bytesReadFromDisk, runs[0].bytesReadFromDisk + runs[1].bytesReadFromDisk + runs[2].bytesReadFromDisk);
    fs::remove(model);
}

TEST(FlightRuns, AResultSentAsJsonGivesTheSameCsv) {
    const fs::path model = testing::writeTemp("json.cvox", testing::cvoxBytes(testing::spherePyramid(64, 5)));
    apps::FlyOptions o = sphereFlight(model);
    o.firstFrame = 2, o.runFrames = 5;  // ends the path: settling frames too
    const apps::FlyResult r = apps::runFly(o);
    const apps::FlyResult back = apps::flyResultFromJson(nlohmann::json::parse(apps::flyResultJson(r).dump()));
    EXPECT_EQ(apps::flyCsv(back), apps::flyCsv(r));
    EXPECT_EQ(apps::flyResultJson(back), apps::flyResultJson(r));
    fs::remove(model);
}

TEST(FlightRuns, ARunOutsideThePathIsRefused) {
    apps::FlyOptions o = sphereFlight("missing.cvox");
    for (const auto& [first, count] : std::vector<std::pair<int, int>>{{-1, 2}, {7, 1}, {5, 3}, {0, -1}}) {
        o.firstFrame = first, o.runFrames = count;
        try {
            apps::runFly(o);
            ADD_FAILURE() << first << " + " << count << " was flown";
        } catch (const scene::InputError& e) {
            EXPECT_NE(std::string(e.what()).find("outside the path"), std::string::npos) << e.what();
        }
    }
}

}  // namespace
}  // namespace cuberille
