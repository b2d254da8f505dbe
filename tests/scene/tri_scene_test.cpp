#include <gtest/gtest.h>

#include "scene/input_error.h"
#include "scene/tri_scene.h"

namespace cuberille::scene {
namespace {

std::string errorOf(const std::string& text) {
    try {
        parseTriScene(text, "scene.tri");
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

TEST(TriScene, ParsesGreyAndRgbLinesWithComments) {
    const TriScene s = parseTriScene("# header\n0 0 1 0 0 1 0.5\n\n1 1 2 1 1 2 0.1 0.2 0.3 # c\n", "t.tri");
    ASSERT_EQ(s.triangleCount(), 2u);
    EXPECT_EQ(s.colors[0], glm::vec4(0.5f, 0.5f, 0.5f, 1.0f));
    EXPECT_EQ(s.colors[1], glm::vec4(0.1f, 0.2f, 0.3f, 1.0f));
    EXPECT_EQ(s.positions[4], glm::vec3(2, 1, 0));
}

TEST(TriScene, MalformedLinesNameFileAndLine) {
    EXPECT_EQ(errorOf("0 0 1 0 0 1 1\n0 0 1 0 0 1\n"),
              "scene.tri:2: expected 7 numbers (x0 y0 x1 y1 x2 y2 v) or 9 (... r g b), found 6");
    EXPECT_EQ(errorOf("# ok\n\n0 0 1 zero 0 1 1\n"), "scene.tri:3: 'zero' is not a number");
    EXPECT_EQ(errorOf("0 0 1 0 0 1 nan\n"), "scene.tri:1: 'nan' is not a finite number");
    EXPECT_EQ(errorOf("0 0 1 0 0 1 1e99\n"), "scene.tri:1: '1e99' is not a number");
    EXPECT_EQ(errorOf("0 0 1 0 0 1 1 1\n"),
              "scene.tri:1: expected 7 numbers (x0 y0 x1 y1 x2 y2 v) or 9 (... r g b), found 8");
}

TEST(TriScene, MissingFileIsAnInputError) {
    EXPECT_THROW(loadTriScene("/nonexistent/scene.tri"), InputError);
}

}  // namespace
}  // namespace cuberille::scene
