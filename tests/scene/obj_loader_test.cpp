// OBJ: face forms, negative indices, polygons as fans, materials from MTL, and errors that name
// the line.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "scene/input_error.h"
#include "scene/obj_loader.h"
#include "tests/temp_paths.h"

namespace cuberille::scene {
namespace {

namespace fs = std::filesystem;

std::vector<Mesh> parse(const std::string& text, std::vector<std::string>* warnings = nullptr,
                        const fs::path& dir = fs::temp_directory_path()) {
    return parseObj(text, "t.obj", dir, [&](const std::string& w) {
        if (warnings) warnings->push_back(w);
    });
}

TEST(ObjLoader, FaceFormsNegativeIndicesAndFans) {
    const auto meshes = parse(
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\n"
        "f 1 2 3 4\n"            // quad → two triangles
        "f -4/1/1 -3//1 -2/1\n"  // relative indices, mixed forms
    );
    ASSERT_EQ(meshes.size(), 1u);
    ASSERT_EQ(meshes[0].triangleCount(), 3u);
    // Which vertices, in which order: the quad as the fan (1 2 3) (1 3 4), then -4 -3 -2 of the
    // four vertices read so far, which are 1 2 3.
    const glm::vec3 v1(0, 0, 0), v2(1, 0, 0), v3(1, 1, 0), v4(0, 1, 0);
    const std::vector<glm::vec3> expected = {v1, v2, v3, v1, v3, v4, v1, v2, v3};
    std::vector<glm::vec3> corners;
    for (uint32_t i : meshes[0].indices) corners.push_back(meshes[0].positions[i]);
    EXPECT_EQ(corners, expected);
    EXPECT_TRUE(meshes[0].colors.empty());
    for (const glm::vec3& n : meshes[0].normals) EXPECT_NEAR(glm::length(n), 1.0f, 1e-5f);
}

TEST(ObjLoader, MaterialsFromMtlSplitMeshesInOrderOfFirstUse) {
    const fs::path dir = cuberille::testing::uniqueTempPath("obj-test");
    fs::create_directories(dir);
    std::ofstream(dir / "m.mtl") << "newmtl red\nKd 1 0 0\nnewmtl grey\nKd 0.5 0.5 0.5\n";
    const auto meshes = parse("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"
                              "usemtl grey\nf 1 2 3\nusemtl red\nf 1 3 2\nusemtl grey\nf 2 3 1\n",
                              nullptr, dir);
    fs::remove_all(dir);
    ASSERT_EQ(meshes.size(), 2u);
    EXPECT_EQ(meshes[0].triangleCount(), 2u);  // grey, used first
    EXPECT_NEAR(meshes[0].color.r, 0.2140f, 1e-3f);
    EXPECT_EQ(meshes[1].color, glm::vec3(1, 0, 0));
}

TEST(ObjLoader, MissingMtlWarnsAndFallsBack) {
    std::vector<std::string> warnings;
    const auto meshes = parse("mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n", &warnings);
    ASSERT_EQ(meshes.size(), 1u);
    EXPECT_EQ(meshes[0].color, glm::vec3(0.8f));
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("nowhere.mtl"), std::string::npos);
}

TEST(ObjLoader, AnMtlNamingAFolderWarnsAndFallsBack) {
    // Found by fuzz_obj: an `mtllib` name cut short by a NUL names the OBJ's own folder, which
    // the reader once took for a file of a nonsense size and failed to allocate.
    const fs::path dir = cuberille::testing::uniqueTempPath("obj-mtl-folder");
    fs::create_directories(dir / "materials.mtl");
    for (const std::string& mtllib : {std::string("mtllib materials.mtl\n"), std::string("mtllib \0\0fuzz.mtl\n", 18)}) {
        std::vector<std::string> warnings;
        const auto meshes = parse(mtllib + "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n", &warnings, dir);
        ASSERT_EQ(meshes.size(), 1u);
        EXPECT_EQ(meshes[0].color, glm::vec3(0.8f));
        EXPECT_EQ(warnings.size(), 1u);
    }
    fs::remove_all(dir);
}

TEST(ObjLoader, ErrorsNameTheLine) {
    auto errorOf = [](const std::string& text) -> std::string {
        try {
            parse(text);
        } catch (const InputError& e) {
            return e.what();
        }
        return "";
    };
    EXPECT_EQ(errorOf("v 0 0 0\nv 1 0 0\nf 1 2 3\n"), "t.obj:3: vertex index 3 is out of range (2 defined so far)");
    EXPECT_EQ(errorOf("v 0 0\n"), "t.obj:1: a vertex needs x y z (and optionally r g b)");
    EXPECT_EQ(errorOf("v 0 0 x\n"), "t.obj:1: 'x' is not a finite number");
    EXPECT_EQ(errorOf("v 0 0 0\nf 1 0 1\n"), "t.obj:2: '0' is not a valid vertex index");
    EXPECT_EQ(errorOf("v 0 0 0\n"), "t.obj: no triangles (no face lines)");
}

}  // namespace
}  // namespace cuberille::scene
