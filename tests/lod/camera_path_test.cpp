// Camera paths: the orbit closes and keeps its distance, the zoom approaches monotonically, files
// parse and bad lines are named.

#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "lod/camera_path.h"
#include "scene/input_error.h"

namespace cuberille {
namespace {

scene::Camera framing() {
    scene::Camera c;
    c.position = {1.0f, 2.0f, 9.0f};
    c.target = {1.0f, 0.5f, 0.0f};
    return c;
}

TEST(CameraPath, OrbitClosesAndKeepsItsDistance) {
    const lod::CameraPath p = lod::CameraPath::orbit(framing());
    const float d = glm::distance(framing().position, framing().target);
    for (float t = 0.0f; t <= 1.0f; t += 0.01f) {
        const scene::Camera c = p.at(t, framing());
        EXPECT_NEAR(glm::distance(c.position, c.target), d, d * 0.01f) << t;
        EXPECT_NEAR(c.position.y, framing().position.y, 1e-4f);
    }
    EXPECT_LT(glm::distance(p.at(1.0f, framing()).position, framing().position), 1e-4f);
    EXPECT_GT(glm::distance(p.at(0.5f, framing()).position, framing().position), d);
}

TEST(CameraPath, ZoomApproachesTheTarget) {
    const lod::CameraPath p = lod::CameraPath::zoom(framing());
    float last = 1e30f;
    for (float t = 0.0f; t <= 1.0f; t += 0.05f) {
        const float d = glm::distance(p.at(t, framing()).position, framing().target);
        EXPECT_LT(d, last);
        last = d;
    }
}

TEST(CameraPath, ReadsKeyframesAndNamesBadLines) {
    const auto dir = std::filesystem::path(::testing::TempDir());
    const auto good = dir / ("cuberille_path_" + std::to_string(::getpid()) + ".txt");
    std::ofstream(good) << "# a path\n0 0 10  0 0 0\n\n10 0 0  0 0 0   # a comment\n";
    const lod::CameraPath p = lod::CameraPath::fromFile(good);
    ASSERT_EQ(p.keys().size(), 2u);
    EXPECT_EQ(p.at(0.5f, framing()).position, glm::vec3(5.0f, 0.0f, 5.0f));
    const auto bad = dir / ("cuberille_badpath_" + std::to_string(::getpid()) + ".txt");
    std::ofstream(bad) << "0 0 10 0 0 0\n1 2 x 0 0 0\n";
    try {
        lod::CameraPath::fromFile(bad);
        ADD_FAILURE() << "accepted a bad line";
    } catch (const scene::InputError& e) {
        EXPECT_NE(std::string(e.what()).find(bad.string() + ":2"), std::string::npos) << e.what();
    }
    std::ofstream(bad) << "0 0 10 0 0 0\n";
    EXPECT_THROW(lod::CameraPath::fromFile(bad), scene::InputError);
    std::filesystem::remove(good);
    std::filesystem::remove(bad);
}

}  // namespace
}  // namespace cuberille
