// glTF: node transforms (including a mirroring one), strips and fans, indexed and not, vertex
// colours, points skipped with a warning, and corrupt accessors reported, on files the test
// writes itself.

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>

#include <webp/encode.h>

#include "apps/image_io.h"
#include "scene/gltf_loader.h"
#include "scene/input_error.h"
#include "tests/scene/gltf_builder.h"
#include "tests/temp_paths.h"

namespace cuberille::scene {
namespace {

namespace fs = std::filesystem;

using testing::base64;

// Buffer: 4 positions (a unit square in z = 0: 0 1 2 3 as a strip, 0 1 3 2 as a fan, both
// counter-clockwise from +z), 4 RGBA8 colours, 4 unsigned-byte indices, animation keys.
std::string bufferBytes() {
    const float p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    std::string b(reinterpret_cast<const char*>(p), sizeof p);
    const uint8_t c[16] = {255, 0, 0, 255, 0, 255, 0, 255, 0, 0, 255, 255, 255, 255, 255, 255};
    b.append(reinterpret_cast<const char*>(c), sizeof c);
    const uint8_t idx[4] = {0, 1, 3, 2};  // the triangle uses the first 3, the fan all 4
    b.append(reinterpret_cast<const char*>(idx), sizeof idx);
    // Animation of node 1 at byte 68: times {0, 1}; translation (0,0,0) → (0,2,0); rotation
    // identity → 90° about z; scale (1,1,1) → (2,2,2), STEP.
    const float s = 0.70710678f;
    const float anim[22] = {0, 1, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1, 0, 0, s, s, 1, 1, 1, 2, 2, 2};
    b.append(reinterpret_cast<const char*>(anim), sizeof anim);
    return b;
}

std::string gltf(const std::string& positionCount = "4") {
    const std::string b = bufferBytes();
    return R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0]}],
  "nodes": [
    {"translation": [10, 0, 0], "children": [1, 2, 3]},
    {"mesh": 0},
    {"mesh": 0, "scale": [-1, 1, 1]},
    {"camera": 0, "translation": [0, 0, 5], "rotation": [0, 0.7071068, 0, 0.7071068]}
  ],
  "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1, "zfar": 100}}],
  "meshes": [{"primitives": [
    {"attributes": {"POSITION": 0, "COLOR_0": 1}, "mode": 5},
    {"attributes": {"POSITION": 0}, "indices": 3, "mode": 6, "material": 0},
    {"attributes": {"POSITION": 0}, "indices": 2},
    {"attributes": {"POSITION": 0}, "mode": 0}
  ]}],
  "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.25, 1, 1]}, "doubleSided": true,
                 "alphaMode": "MASK", "alphaCutoff": 0.3,
                 "extensions": {"KHR_materials_unlit": {}}}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": )" + positionCount + R"(, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
    {"bufferView": 1, "componentType": 5121, "normalized": true, "count": 4, "type": "VEC4"},
    {"bufferView": 2, "componentType": 5121, "count": 3, "type": "SCALAR"},
    {"bufferView": 2, "componentType": 5121, "count": 4, "type": "SCALAR"},
    {"bufferView": 3, "byteOffset": 0, "componentType": 5126, "count": 2, "type": "SCALAR"},
    {"bufferView": 3, "byteOffset": 8, "componentType": 5126, "count": 2, "type": "VEC3"},
    {"bufferView": 3, "byteOffset": 32, "componentType": 5126, "count": 2, "type": "VEC4"},
    {"bufferView": 3, "byteOffset": 64, "componentType": 5126, "count": 2, "type": "VEC3"}
  ],
  "animations": [{
    "samplers": [{"input": 4, "output": 5}, {"input": 4, "output": 6}, {"input": 4, "output": 7, "interpolation": "STEP"}],
    "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}},
                 {"sampler": 1, "target": {"node": 1, "path": "rotation"}},
                 {"sampler": 2, "target": {"node": 1, "path": "scale"}}]
  }],
  "bufferViews": [
    {"buffer": 0, "byteOffset": 0, "byteLength": 48},
    {"buffer": 0, "byteOffset": 48, "byteLength": 16},
    {"buffer": 0, "byteOffset": 64, "byteLength": 4},
    {"buffer": 0, "byteOffset": 68, "byteLength": 88}
  ],
  "buffers": [{"byteLength": )" + std::to_string(b.size()) + R"(, "uri": "data:application/octet-stream;base64,)" + base64(b) + R"("}]
})";
}

// Replaces the one occurrence of `from` (a test-authoring error, reported, when absent).
void replaceOnce(std::string& text, const std::string& from, const std::string& to) {
    const size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
}

fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = cuberille::testing::uniqueTempPath(name);
    std::ofstream(p) << text;
    return p;
}

// Signed area in the xy plane (positive = counter-clockwise seen from +z).
float area(const Mesh& m, size_t t) {
    const glm::vec3 a = m.positions[m.indices[3 * t]], b = m.positions[m.indices[3 * t + 1]],
                    c = m.positions[m.indices[3 * t + 2]];
    return (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
}

// Two animations: the file's own (named "turn": translation, rotation, scale of node 1) and
// "lift" (its translation alone). Either is chosen by name or by index; the default is the
// first; a name or index the file lacks is an InputError naming what it has.
TEST(GltfLoader, AnAnimationIsChosenByNameOrIndex) {
    std::string text = gltf();
    replaceOnce(text, R"("animations": [{
    "samplers")", R"("animations": [{"name": "turn",
    "samplers")");
    replaceOnce(text, R"(                 {"sampler": 2, "target": {"node": 1, "path": "scale"}}]
  }],)", R"(                 {"sampler": 2, "target": {"node": 1, "path": "scale"}}]
  }, {"name": "lift", "samplers": [{"input": 4, "output": 5}],
      "channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}]}],)");
    const fs::path path = write("two-animations.gltf", text);
    std::vector<std::string> warnings;
    const WarningSink warn = [&](const std::string& w) { warnings.push_back(w); };
    auto positions = [&](const std::string& animation) {
        std::vector<glm::vec3> all;
        for (const Mesh& m : loadGltf(path, warn, 1.0f, animation).meshes) all.insert(all.end(), m.positions.begin(), m.positions.end());
        return all;
    };
    const auto byDefault = positions(""), turn = positions("turn"), lift = positions("lift");
    EXPECT_EQ(byDefault, turn);
    EXPECT_NE(turn, lift);  // lift neither turns nor scales node 1
    EXPECT_EQ(positions("0"), turn);
    EXPECT_EQ(positions("1"), lift);
    for (const std::string missing : {"spin", "2", "-1"}) {
        try {
            positions(missing);
            ADD_FAILURE() << "accepted animation " << missing;
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("'" + missing + "'"), std::string::npos) << what;
            EXPECT_NE(what.find("0 'turn', 1 'lift'"), std::string::npos) << what;
        }
    }
    // Only the default of several is warned about, and the warning names the option.
    warnings.clear();
    loadGltf(path, warn, 1.0f, "");
    ASSERT_FALSE(warnings.empty());
    EXPECT_NE(warnings.front().find("--animation"), std::string::npos) << warnings.front();
    warnings.clear();
    loadGltf(path, warn, 1.0f, "lift");
    for (const std::string& w : warnings) EXPECT_EQ(w.find("--animation"), std::string::npos) << w;
}

TEST(GltfLoader, HierarchyStripsFansIndicesColoursAndMirroring) {
    std::vector<std::string> warnings;
    const GltfScene scene = loadGltf(write("cuberille-test.gltf", gltf()), [&](const std::string& w) { warnings.push_back(w); });
    const auto& meshes = scene.meshes;
    // 2 nodes x 3 drawable primitives; the POINTS primitive is skipped with one warning.
    ASSERT_EQ(meshes.size(), 6u);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("points and lines are skipped"), std::string::npos);
    const size_t triangles[3] = {2, 2, 1};  // strip of 4, fan of 4, one indexed triangle
    for (size_t i = 0; i < 6; ++i) {
        const Mesh& m = meshes[i];
        EXPECT_EQ(m.triangleCount(), triangles[i % 3]) << i;
        const bool mirrored = i >= 3;
        EXPECT_EQ(m.positions[1], mirrored ? glm::vec3(9, 0, 0) : glm::vec3(11, 0, 0)) << i;
        for (size_t t = 0; t < m.triangleCount(); ++t) {
            // Mirroring flips the geometry; the loader flips the order back, so the facing
            // (counter-clockwise from +z, the normal's side) is kept.
            EXPECT_GT(area(m, t), 0.0f) << "mesh " << i << " triangle " << t;
        }
        for (const glm::vec3& n : m.normals) EXPECT_NEAR(n.z, 1.0f, 1e-5f);
    }
    EXPECT_EQ(meshes[0].colors.size(), 4u);
    EXPECT_EQ(meshes[0].colors[1], glm::vec3(0, 1, 0));
    EXPECT_EQ(meshes[1].color, glm::vec3(0.5f, 0.25f, 1.0f));
    EXPECT_TRUE(meshes[1].doubleSided);
    EXPECT_FALSE(meshes[2].doubleSided);
    EXPECT_TRUE(meshes[1].unlit);  // KHR_materials_unlit
    EXPECT_EQ(meshes[1].alphaMode, raster::AlphaMode::Mask);
    EXPECT_FLOAT_EQ(meshes[1].alphaCutoff, 0.3f);
    EXPECT_EQ(meshes[2].alphaMode, raster::AlphaMode::Opaque);
    EXPECT_FALSE(meshes[2].unlit);

    // The camera node sits at (10, 0, 5), turned 90 degrees about +y: it looks down world -x.
    ASSERT_EQ(scene.cameras.size(), 1u);
    const Camera& c = scene.cameras[0];
    EXPECT_NEAR(glm::distance(c.position, glm::vec3(10, 0, 5)), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::distance(c.target - c.position, glm::vec3(-1, 0, 0)), 0.0f, 1e-5f);
    EXPECT_NEAR(c.verticalFovDegrees, glm::degrees(0.5f), 1e-4f);
    EXPECT_EQ(c.farPlane, 100.0f);
}

// The fixture with a 2x1 PNG (sRGB 255 and 128 in red) beside it as texture 0 (its sampler:
// clamp in u, mirrored in v, nearest magnification), and TEXCOORD_0 on the fan (the positions'
// x and y). `materialJson` replaces the fan's material's baseColorFactor entry.
std::string texturedGltf(const fs::path& dir, const std::string& materialJson) {
    fs::create_directories(dir);
    raster::Image png;
    png.width = 2;
    png.height = 1;
    png.rgba = {1.0f, 0, 0, 1, 0.21586f, 0, 0, 1};  // linear; written as sRGB 255 and 128
    apps::writeImageAtomically(dir / "tex.png", png);
    std::string text = gltf();
    replaceOnce(text, R"("materials": [{)", R"("textures": [{"source": 0, "sampler": 0}], "images": [{"uri": "tex.png"}],
  "samplers": [{"wrapS": 33071, "wrapT": 33648, "magFilter": 9728}],
  "materials": [{)");
    replaceOnce(text, R"("baseColorFactor": [0.5, 0.25, 1, 1]})", materialJson);
    replaceOnce(text, R"({"attributes": {"POSITION": 0}, "indices": 3)",
         R"({"attributes": {"POSITION": 0, "TEXCOORD_0": 8}, "indices": 3)");
    replaceOnce(text, R"({"bufferView": 3, "byteOffset": 64, "componentType": 5126, "count": 2, "type": "VEC3"})",
         R"({"bufferView": 3, "byteOffset": 64, "componentType": 5126, "count": 2, "type": "VEC3"},
    {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC2"})");
    replaceOnce(text, R"({"buffer": 0, "byteOffset": 0, "byteLength": 48})",
         R"({"buffer": 0, "byteOffset": 0, "byteLength": 48, "byteStride": 12})");
    return text;
}

TEST(GltfLoader, BaseColorTextureIsDecodedToLinearWithItsSampler) {
    const fs::path dir = cuberille::testing::uniqueTempPath("gltf-texture");
    const std::string text = texturedGltf(dir,
        R"("baseColorFactor": [0.5, 0.25, 1, 1], "baseColorTexture": {"index": 0}})");
    std::ofstream(dir / "t.gltf") << text;
    const GltfScene scene = loadGltf(dir / "t.gltf", [](const std::string&) {});
    fs::remove_all(dir);
    const Mesh& fan = scene.meshes[1];
    ASSERT_TRUE(fan.textures.baseColor);
    ASSERT_EQ(fan.texCoords.size(), 4u);
    EXPECT_EQ(fan.texCoords[3], glm::vec2(1, 1));  // x, y of position 3 read as u, v
    const raster::Texture& t = *fan.textures.baseColor.texture;
    ASSERT_EQ(t.width(), 2);
    EXPECT_FLOAT_EQ(t.texel(0, 0, 0).r, 1.0f);
    EXPECT_NEAR(t.texel(0, 1, 0).r, 0.2158f, 1e-3f);  // sRGB 128 decoded
    // Clamp in u: far right samples the last texel; mirrored in v (one row: always that row).
    EXPECT_EQ(t.sampleBilinear(0, glm::vec2(7.0f, 0.5f)), t.texel(0, 1, 0));
    EXPECT_FALSE(scene.meshes[0].textures.baseColor) << "untextured primitives stay untextured";
}

// texturedGltf's fixture with its material's unlit extension replaced by `extension` holding
// `json`, written to `path`; `pbr` replaces the material's metallic-roughness entries.
void writeWithMaterialExtension(const fs::path& dir, const std::string& extension, const std::string& json, const fs::path& path,
                                const std::string& pbr = R"("baseColorFactor": [0.9, 0.9, 0.9, 1]})") {
    std::string text = texturedGltf(dir, pbr);
    replaceOnce(text, R"("extensions": {"KHR_materials_unlit": {}})", R"("extensions": {")" + extension + R"(": {)" + json + "}}");
    std::ofstream(path) << text;
}

// The file is refused with an InputError whose message names `extension`.
void expectRefusedNaming(const fs::path& path, const std::string& extension, const std::string& what) {
    try {
        loadGltf(path, [](const std::string&) {});
        ADD_FAILURE() << what << " was read";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(extension), std::string::npos) << e.what();
    }
}

// KHR_materials_pbrSpecularGlossiness: where a material has it, its factors and textures are read
// in place of the metallic-roughness ones — the diffuse texture in the base colour slot, the
// specular-glossiness texture (sRGB colour, linear alpha) in the metallic-roughness slot, both
// decoded from sRGB — and a factor outside [0, 1] or a texture the file lacks is refused.
TEST(GltfLoader, SpecularGlossinessReplacesMetallicRoughnessAndBadValuesAreRefused) {
    const fs::path dir = cuberille::testing::uniqueTempPath("gltf-specgloss");
    // The fixture's material given the extension (its metallic-roughness factors and texture
    // stay, to be ignored).
    auto write = [&](const std::string& ext, const fs::path& path) {
        writeWithMaterialExtension(dir, "KHR_materials_pbrSpecularGlossiness", ext, path,
                                   R"("baseColorFactor": [0.9, 0.9, 0.9, 1], "metallicRoughnessTexture": {"index": 0}})");
    };
    write(R"("diffuseFactor": [0.5, 0.25, 1, 0.8], "specularFactor": [0.2, 0.3, 0.4], "glossinessFactor": 0.6,
             "diffuseTexture": {"index": 0}, "specularGlossinessTexture": {"index": 0})",
          dir / "t.gltf");
    const GltfScene scene = loadGltf(dir / "t.gltf", [](const std::string&) {});
    const Mesh& fan = scene.meshes[1];
    EXPECT_TRUE(fan.brdf.specularGlossiness);
    EXPECT_EQ(fan.color, glm::vec3(0.5f, 0.25f, 1.0f));
    EXPECT_EQ(fan.alpha, 0.8f);
    EXPECT_EQ(fan.brdf.specularFactor, glm::vec3(0.2f, 0.3f, 0.4f));
    EXPECT_EQ(fan.brdf.glossiness, 0.6f);
    ASSERT_TRUE(fan.textures.baseColor);
    ASSERT_TRUE(fan.textures.metallicRoughness);
    EXPECT_NEAR(fan.textures.metallicRoughness.texture->texel(0, 1, 0).r, 0.2158f, 1e-3f) << "specular decoded from sRGB";
    EXPECT_EQ(fan.textures.metallicRoughness.texture->texel(0, 1, 0).a, 1.0f) << "glossiness linear";
    EXPECT_FALSE(scene.meshes[0].brdf.specularGlossiness);
    for (const std::string bad : {R"("specularFactor": [2, 0, 0])", R"("glossinessFactor": "shiny")", R"("diffuseFactor": [1, 1, 1])",
                                  R"("diffuseTexture": {"index": 7})"}) {
        write(bad, dir / "bad.gltf");
        expectRefusedNaming(dir / "bad.gltf", "KHR_materials_pbrSpecularGlossiness", bad);
    }
    fs::remove_all(dir);
}

// KHR_materials_specular: the strength and F0 colour factors (a colour past 1 allowed), the
// specular texture read linear (its alpha is the strength) and the specular colour texture
// decoded from sRGB; a strength outside [0, 1] or a negative colour is refused.
TEST(GltfLoader, DielectricSpecularIsReadAndBadValuesAreRefused) {
    const fs::path dir = cuberille::testing::uniqueTempPath("gltf-specular");
    auto write = [&](const std::string& ext, const fs::path& path) { writeWithMaterialExtension(dir, "KHR_materials_specular", ext, path); };
    write(R"("specularFactor": 0.25, "specularColorFactor": [2, 1, 0.5], "specularTexture": {"index": 0},
             "specularColorTexture": {"index": 0})",
          dir / "t.gltf");
    const GltfScene scene = loadGltf(dir / "t.gltf", [](const std::string&) {});
    const Mesh& fan = scene.meshes[1];
    EXPECT_TRUE(fan.brdf.dielectricSpecular);
    EXPECT_EQ(fan.brdf.specularStrength, 0.25f);
    EXPECT_EQ(fan.brdf.specularColor, glm::vec3(2.0f, 1.0f, 0.5f));
    ASSERT_TRUE(fan.textures.specular);
    ASSERT_TRUE(fan.textures.specularColor);
    EXPECT_NEAR(fan.textures.specular.texture->texel(0, 1, 0).r, 128.0f / 255.0f, 1e-6f) << "read linear";
    EXPECT_NEAR(fan.textures.specularColor.texture->texel(0, 1, 0).r, 0.2158f, 1e-3f) << "decoded from sRGB";
    EXPECT_FALSE(scene.meshes[0].brdf.dielectricSpecular);
    for (const std::string bad : {R"("specularFactor": 1.5)", R"("specularColorFactor": [1, -1, 1])", R"("specularColorFactor": [1, 1])",
                                  R"("specularTexture": {"index": 3})"}) {
        write(bad, dir / "bad.gltf");
        expectRefusedNaming(dir / "bad.gltf", "KHR_materials_specular", bad);
    }
    fs::remove_all(dir);
}

// KHR_materials_clearcoat: weight and roughness factors and their linear textures, its own normal
// map with its scale (and tangents for it); a zero weight disables the layer (its textures
// unbound); a factor outside [0, 1] is refused.
TEST(GltfLoader, ClearcoatIsReadAndBadValuesAreRefused) {
    const fs::path dir = cuberille::testing::uniqueTempPath("gltf-clearcoat");
    auto write = [&](const std::string& ext, const fs::path& path) { writeWithMaterialExtension(dir, "KHR_materials_clearcoat", ext, path); };
    write(R"("clearcoatFactor": 0.75, "clearcoatRoughnessFactor": 0.2, "clearcoatTexture": {"index": 0},
             "clearcoatRoughnessTexture": {"index": 0}, "clearcoatNormalTexture": {"index": 0, "scale": 0.5})",
          dir / "t.gltf");
    std::vector<std::string> warnings;
    const GltfScene scene = loadGltf(dir / "t.gltf", [&](const std::string& w) { warnings.push_back(w); });
    const Mesh& fan = scene.meshes[1];
    EXPECT_EQ(fan.brdf.clearcoat, 0.75f);
    EXPECT_EQ(fan.brdf.clearcoatRoughness, 0.2f);
    ASSERT_TRUE(fan.textures.clearcoat);
    ASSERT_TRUE(fan.textures.clearcoatRoughness);
    EXPECT_NEAR(fan.textures.clearcoat.texture->texel(0, 1, 0).r, 128.0f / 255.0f, 1e-6f) << "read linear";
    ASSERT_TRUE(fan.textures.clearcoatNormal);
    EXPECT_EQ(fan.brdf.clearcoatNormalScale, 0.5f);
    EXPECT_EQ(fan.tangents.size(), fan.positions.size()) << "tangents for the coat's normal map";
    for (const std::string& w : warnings) EXPECT_EQ(w.find("KHR_materials_clearcoat"), std::string::npos) << w;
    EXPECT_EQ(scene.meshes[0].brdf.clearcoat, 0.0f);
    write(R"("clearcoatFactor": 0, "clearcoatTexture": {"index": 0})", dir / "off.gltf");
    const GltfScene off = loadGltf(dir / "off.gltf", [](const std::string&) {});
    EXPECT_EQ(off.meshes[1].brdf.clearcoat, 0.0f);
    EXPECT_FALSE(off.meshes[1].textures.clearcoat) << "a zero weight disables the layer";
    for (const std::string bad : {R"("clearcoatFactor": 1.5)", R"("clearcoatRoughnessFactor": -0.1)", R"("clearcoatFactor": [1])",
                                  R"("clearcoatFactor": 1, "clearcoatNormalTexture": {"index": 0, "scale": "big"})"}) {
        write(bad, dir / "bad.gltf");
        expectRefusedNaming(dir / "bad.gltf", "KHR_materials_clearcoat", bad);
    }
    fs::remove_all(dir);
}

// KHR_materials_sheen: the colour factor and its sRGB texture, the roughness factor and its linear
// texture; a zero colour disables the layer (its textures unbound); a factor outside [0, 1] is
// refused.
TEST(GltfLoader, SheenIsReadAndBadValuesAreRefused) {
    const fs::path dir = cuberille::testing::uniqueTempPath("gltf-sheen");
    auto write = [&](const std::string& ext, const fs::path& path) { writeWithMaterialExtension(dir, "KHR_materials_sheen", ext, path); };
    write(R"("sheenColorFactor": [1, 0.5, 0.25], "sheenRoughnessFactor": 0.4, "sheenColorTexture": {"index": 0},
             "sheenRoughnessTexture": {"index": 0})",
          dir / "t.gltf");
    std::vector<std::string> warnings;
    const GltfScene scene = loadGltf(dir / "t.gltf", [&](const std::string& w) { warnings.push_back(w); });
    const Mesh& fan = scene.meshes[1];
    EXPECT_EQ(fan.brdf.sheenColor, glm::vec3(1.0f, 0.5f, 0.25f));
    EXPECT_EQ(fan.brdf.sheenRoughness, 0.4f);
    ASSERT_TRUE(fan.textures.sheenColor);
    ASSERT_TRUE(fan.textures.sheenRoughness);
    EXPECT_NEAR(fan.textures.sheenColor.texture->texel(0, 1, 0).r, 0.2158f, 1e-3f) << "decoded from sRGB";
    EXPECT_NEAR(fan.textures.sheenRoughness.texture->texel(0, 1, 0).r, 128.0f / 255.0f, 1e-6f) << "read linear";
    for (const std::string& w : warnings) EXPECT_EQ(w.find("KHR_materials_sheen"), std::string::npos) << w;
    EXPECT_EQ(scene.meshes[0].brdf.sheenColor, glm::vec3(0.0f));
    write(R"("sheenRoughnessFactor": 0.5, "sheenColorTexture": {"index": 0})", dir / "off.gltf");
    const GltfScene off = loadGltf(dir / "off.gltf", [](const std::string&) {});
    EXPECT_EQ(off.meshes[1].brdf.sheenColor, glm::vec3(0.0f));
    EXPECT_FALSE(off.meshes[1].textures.sheenColor) << "a zero colour (the default) disables the layer";
    for (const std::string bad : {R"("sheenColorFactor": [1, 2, 1])", R"("sheenRoughnessFactor": -0.1)", R"("sheenColorFactor": 1)",
                                  R"("sheenColorFactor": [1, 1, 1], "sheenRoughnessTexture": {"index": 7})"}) {
        write(bad, dir / "bad.gltf");
        expectRefusedNaming(dir / "bad.gltf", "KHR_materials_sheen", bad);
    }
    fs::remove_all(dir);
}

// KHR_materials_transmission with KHR_materials_volume: the share and its linear texture, the
// thickness in world units (the mirrored node's scale (-1, 1, 1) keeps it; (-2, 2, 2), 8 in
// volume, doubles it) with its texture, the attenuation colour and distance; a transmissive mesh is
// drawn after the opaque ones (seeThrough); a zero share disables both; bad values are refused.
TEST(GltfLoader, TransmissionAndVolumeAreReadInWorldUnitsAndBadValuesAreRefused) {
    const fs::path dir = cuberille::testing::uniqueTempPath("gltf-transmission");
    auto write = [&](const std::string& ext, const fs::path& path) {
        writeWithMaterialExtension(dir, "KHR_materials_transmission", ext, path);
    };
    const std::string both = R"("transmissionFactor": 0.75, "transmissionTexture": {"index": 0}},
        "KHR_materials_volume": {"thicknessFactor": 0.5, "thicknessTexture": {"index": 0}, "attenuationColor": [1, 0.5, 0.25],
                                 "attenuationDistance": 3)";
    write(both, dir / "t.gltf");
    std::vector<std::string> warnings;
    const GltfScene scene = loadGltf(dir / "t.gltf", [&](const std::string& w) { warnings.push_back(w); });
    for (const size_t fan : {1u, 4u}) {  // the fan under each node
        const Mesh& m = scene.meshes[fan];
        EXPECT_EQ(m.brdf.transmission, 0.75f);
        EXPECT_TRUE(m.seeThrough());
        ASSERT_TRUE(m.textures.transmission);
        EXPECT_NEAR(m.textures.transmission.texture->texel(0, 1, 0).r, 128.0f / 255.0f, 1e-6f) << "read linear";
        EXPECT_NEAR(m.brdf.thickness, 0.5f, 1e-6f);
        ASSERT_TRUE(m.textures.thickness);
        EXPECT_EQ(m.brdf.attenuationColor, glm::vec3(1.0f, 0.5f, 0.25f));
        EXPECT_EQ(m.brdf.attenuationDistance, 3.0f);
    }
    EXPECT_FALSE(scene.meshes[0].seeThrough());
    for (const std::string& w : warnings) EXPECT_EQ(w.find("KHR_materials_"), std::string::npos) << w;
    {
        std::string text = texturedGltf(dir, R"("baseColorFactor": [0.9, 0.9, 0.9, 1]})");
        replaceOnce(text, R"("extensions": {"KHR_materials_unlit": {}})", R"("extensions": {"KHR_materials_transmission": {)" + both + "}}");
        replaceOnce(text, R"({"mesh": 0, "scale": [-1, 1, 1]})", R"({"mesh": 0, "scale": [-2, 2, 2]})");
        std::ofstream(dir / "scaled.gltf") << text;
        EXPECT_NEAR(loadGltf(dir / "scaled.gltf", [](const std::string&) {}).meshes[4].brdf.thickness, 1.0f, 1e-6f);
    }
    write(R"("transmissionFactor": 0, "transmissionTexture": {"index": 0})", dir / "off.gltf");
    const GltfScene off = loadGltf(dir / "off.gltf", [](const std::string&) {});
    EXPECT_EQ(off.meshes[1].brdf.transmission, 0.0f);
    EXPECT_FALSE(off.meshes[1].textures.transmission);
    EXPECT_FALSE(off.meshes[1].seeThrough());
    for (const auto& [bad, names] :
         {std::pair<std::string, std::string>{R"("transmissionFactor": 1.5)", "KHR_materials_transmission"},
          {R"("transmissionFactor": 1}, "KHR_materials_volume": {"thicknessFactor": -1)", "KHR_materials_volume"},
          {R"("transmissionFactor": 1}, "KHR_materials_volume": {"attenuationDistance": 0)", "KHR_materials_volume"},
          {R"("transmissionFactor": 1}, "KHR_materials_volume": {"attenuationColor": [1, 1])", "KHR_materials_volume"}}) {
        write(bad, dir / "bad.gltf");
        expectRefusedNaming(dir / "bad.gltf", names, bad);
    }
    fs::remove_all(dir);
}

// EXT_texture_webp: a texture naming a WebP source reads it (lossless here: the texels exactly)
// in place of its core source, which stays the fallback for readers without WebP; a WebP-only
// texture (the extension required) reads too.
TEST(GltfLoader, WebPTexturesReadInPlaceOfTheirFallback) {
    const fs::path dir = cuberille::testing::uniqueTempPath("gltf-webp");
    std::string text = texturedGltf(dir, R"("baseColorTexture": {"index": 0}})");
    const uint8_t greens[8] = {0, 255, 0, 255, 0, 128, 0, 255};  // the PNG fallback holds reds
    uint8_t* encoded = nullptr;
    const size_t size = WebPEncodeLosslessRGBA(greens, 2, 1, 8, &encoded);
    ASSERT_GT(size, 0u);
    std::ofstream(dir / "tex.webp", std::ios::binary).write(reinterpret_cast<const char*>(encoded), std::streamsize(size));
    WebPFree(encoded);
    for (bool fallback : {true, false}) {
        std::string variant = text;
        replaceOnce(variant, R"("textures": [{"source": 0, "sampler": 0}], "images": [{"uri": "tex.png"}],)",
                    fallback ? R"("textures": [{"source": 0, "sampler": 0, "extensions": {"EXT_texture_webp": {"source": 1}}}],
  "images": [{"uri": "tex.png"}, {"uri": "tex.webp"}], "extensionsUsed": ["EXT_texture_webp"],)"
                             : R"("textures": [{"sampler": 0, "extensions": {"EXT_texture_webp": {"source": 0}}}],
  "images": [{"uri": "tex.webp"}], "extensionsUsed": ["EXT_texture_webp"], "extensionsRequired": ["EXT_texture_webp"],)");
        std::ofstream(dir / "t.gltf") << variant;
        std::vector<std::string> warnings;
        const GltfScene scene = loadGltf(dir / "t.gltf", [&](const std::string& w) { warnings.push_back(w); });
        for (const std::string& w : warnings)  // the shared test file's points and lines warn; nothing else may
            if (w.find("points and lines") == std::string::npos) ADD_FAILURE() << "fallback " << fallback << ": " << w;
        ASSERT_TRUE(scene.meshes[1].textures.baseColor) << "fallback " << fallback;
        const raster::Texture& t = *scene.meshes[1].textures.baseColor.texture;
        ASSERT_EQ(t.width(), 2);
        EXPECT_EQ(t.texel(0, 0, 0), glm::vec4(0, 1, 0, 1)) << "fallback " << fallback;
        EXPECT_NEAR(t.texel(0, 1, 0).g, 0.2158f, 1e-3f);  // sRGB 128 decoded
        EXPECT_EQ(t.texel(0, 1, 0).r, 0.0f);
    }
    fs::remove_all(dir);
}

TEST(GltfLoader, MaterialFactorsTextureSlotsAndTextureTransform) {
    const fs::path dir = cuberille::testing::uniqueTempPath("gltf-material");
    std::string text = texturedGltf(dir, R"("metallicFactor": 0.25, "roughnessFactor": 0.75},
      "normalTexture": {"index": 0, "scale": 0.5},
      "emissiveFactor": [1, 0.5, 0],
      "emissiveTexture": {"index": 0, "extensions": {"KHR_texture_transform": {"offset": [0.5, 0], "scale": [2, 2]}}})");
    replaceOnce(text, R"("extensions": {"KHR_materials_unlit": {}})", R"("extensions": {})");  // unlit reads no other slot
    std::ofstream(dir / "t.gltf") << text;
    std::vector<std::string> warnings;
    const GltfScene scene = loadGltf(dir / "t.gltf", [&](const std::string& w) { warnings.push_back(w); });
    fs::remove_all(dir);
    const Mesh& fan = scene.meshes[1];
    EXPECT_TRUE(fan.metallicRoughness);
    EXPECT_FLOAT_EQ(fan.metallic, 0.25f);
    EXPECT_FLOAT_EQ(fan.roughness, 0.75f);
    EXPECT_EQ(fan.emissive, glm::vec3(1, 0.5f, 0));
    EXPECT_FLOAT_EQ(fan.normalScale, 0.5f);
    // The same image twice: linear for the normal map, sRGB-decoded for emission.
    ASSERT_TRUE(fan.textures.normal);
    ASSERT_TRUE(fan.textures.emissive);
    EXPECT_NEAR(fan.textures.normal.texture->texel(0, 1, 0).r, 128.0f / 255.0f, 1e-6f);
    EXPECT_NEAR(fan.textures.emissive.texture->texel(0, 1, 0).r, 0.2158f, 1e-3f);
    EXPECT_EQ(scene.stats.texturesDecoded, 2u);
    // Nearest magnification from the sampler: no blend between the two texels.
    EXPECT_EQ(fan.textures.normal.texture->sample(glm::vec2(0.45f, 0.5f), -1.0f), fan.textures.normal.texture->texel(0, 0, 0));
    // KHR_texture_transform: uv' = offset + scale * uv.
    EXPECT_EQ(fan.textures.emissive.transform.apply(glm::vec2(0.25f, 0.5f)), glm::vec2(1.0f, 1.0f));
    EXPECT_TRUE(fan.textures.normal.transform.isIdentity());
    // No TANGENT in the file: computed from the UVs, unit length, perpendicular to the normal,
    // along +u (the positions' x).
    ASSERT_EQ(fan.tangents.size(), fan.positions.size());
    for (size_t i = 0; i < fan.tangents.size(); ++i) {
        EXPECT_NEAR(glm::dot(glm::vec3(fan.tangents[i]), fan.normals[i]), 0.0f, 1e-6f);
        EXPECT_NEAR(glm::distance(glm::vec3(fan.tangents[i]), glm::vec3(1, 0, 0)), 0.0f, 1e-6f);
    }
    for (const auto& w : warnings) EXPECT_EQ(w.find("texture"), std::string::npos) << w;
}

TEST(GltfLoader, AnimationPosesNodesAtTheRequestedTime) {
    const fs::path path = write("cuberille-anim.gltf", gltf());
    auto vertex1 = [&](float time) {  // the strip's vertex (1, 0, 0) under node 0 then node 1
        return loadGltf(path, [](const std::string&) {}, time).meshes[0].positions[1];
    };
    const float r = 0.70710678f;
    EXPECT_NEAR(glm::distance(vertex1(0.0f), glm::vec3(11, 0, 0)), 0.0f, 1e-5f);
    // Halfway: translated by (0, 1, 0), rotated 45° about z (slerp), scale still 1 (STEP).
    EXPECT_NEAR(glm::distance(vertex1(0.5f), glm::vec3(10 + r, 1 + r, 0)), 0.0f, 1e-5f);
    // Past the end: clamped to the last key: (0, 2, 0) + R90 (2, 0, 0) = (0, 4, 0).
    EXPECT_NEAR(glm::distance(vertex1(7.0f), glm::vec3(10, 4, 0)), 0.0f, 1e-5f);
    EXPECT_NEAR(glm::distance(vertex1(-1.0f), glm::vec3(11, 0, 0)), 0.0f, 1e-5f);
}

TEST(GltfLoader, SkinBlendsJointMatricesAndIgnoresTheMeshNodeTransform) {
    // One triangle; every vertex 50/50 on joint 0 (translated by (1,0,0)) and joint 1
    // (translated by (0,2,0)); identity inverse bind matrices; the mesh node's (100,0,0) is ignored.
    std::string b;
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    b.append(reinterpret_cast<const char*>(p), sizeof p);
    const uint8_t j[12] = {0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0};
    b.append(reinterpret_cast<const char*>(j), sizeof j);
    const float w[12] = {0.5f, 0.5f, 0, 0, 0.5f, 0.5f, 0, 0, 0.5f, 0.5f, 0, 0};
    b.append(reinterpret_cast<const char*>(w), sizeof w);
    const std::string text = R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
  "nodes": [{"mesh": 0, "skin": 0, "translation": [100, 0, 0]}, {"translation": [1, 0, 0]}, {"translation": [0, 2, 0]}],
  "skins": [{"joints": [1, 2]}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "JOINTS_0": 1, "WEIGHTS_0": 2}}]}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
    {"bufferView": 1, "componentType": 5121, "count": 3, "type": "VEC4"},
    {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC4"}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 12},
                  {"buffer": 0, "byteOffset": 48, "byteLength": 48}],
  "buffers": [{"byteLength": 96, "uri": "data:application/octet-stream;base64,)" + base64(b) + R"("}]})";
    const GltfScene scene = loadGltf(write("cuberille-skin.gltf", text), [](const std::string&) {});
    ASSERT_EQ(scene.meshes.size(), 1u);
    const std::vector<glm::vec3> expected = {{0.5f, 1, 0}, {1.5f, 1, 0}, {0.5f, 2, 0}};
    for (int i = 0; i < 3; ++i)
        EXPECT_NEAR(glm::distance(scene.meshes[0].positions[i], expected[i]), 0.0f, 1e-6f) << i;
}

TEST(GltfLoader, MorphTargetsBlendByMeshNodeAndAnimatedWeights) {
    // One triangle with two targets: +z and +x on every vertex. Node 0 uses the mesh's weights
    // (0.5, 0); node 1 overrides them (0, 1); node 2 is animated from (0, 0) at t=0 to (1, 1) at t=1.
    std::string b;
    const float data[] = {0, 0, 0, 1, 0, 0, 0, 1, 0,   // positions
                          0, 0, 1, 0, 0, 1, 0, 0, 1,   // target 0
                          1, 0, 0, 1, 0, 0, 1, 0, 0,   // target 1
                          0, 1,                         // key times
                          0, 0, 1, 1};                  // key weights (2 per key)
    b.append(reinterpret_cast<const char*>(data), sizeof data);
    const std::string text = R"({"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
  "nodes": [{"mesh": 0}, {"mesh": 0, "weights": [0, 1]}, {"mesh": 0}],
  "meshes": [{"weights": [0.5, 0], "primitives": [{"attributes": {"POSITION": 0},
              "targets": [{"POSITION": 1}, {"POSITION": 2}]}]}],
  "animations": [{"samplers": [{"input": 3, "output": 4}], "channels": [{"sampler": 0, "target": {"node": 2, "path": "weights"}}]}],
  "accessors": [
    {"bufferView": 0, "byteOffset": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]},
    {"bufferView": 0, "byteOffset": 36, "componentType": 5126, "count": 3, "type": "VEC3"},
    {"bufferView": 0, "byteOffset": 72, "componentType": 5126, "count": 3, "type": "VEC3"},
    {"bufferView": 0, "byteOffset": 108, "componentType": 5126, "count": 2, "type": "SCALAR"},
    {"bufferView": 0, "byteOffset": 116, "componentType": 5126, "count": 4, "type": "SCALAR"}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 132}],
  "buffers": [{"byteLength": 132, "uri": "data:application/octet-stream;base64,)" + base64(b) + R"("}]})";
    const fs::path path = write("cuberille-morph.gltf", text);
    const GltfScene at25 = loadGltf(path, [](const std::string&) {}, 0.25f);
    ASSERT_EQ(at25.meshes.size(), 3u);
    EXPECT_EQ(at25.meshes[0].positions[1], glm::vec3(1, 0, 0.5f));     // mesh weights
    EXPECT_EQ(at25.meshes[1].positions[1], glm::vec3(2, 0, 0));        // node weights
    EXPECT_EQ(at25.meshes[2].positions[1], glm::vec3(1.25f, 0, 0.25f)); // animated, a quarter in
}

TEST(GltfLoader, PunctualLightsFromKhrLightsPunctual) {
    std::string text = gltf();
    replaceOnce(text, R"("asset": {"version": "2.0"},)", R"("asset": {"version": "2.0"},
  "extensionsUsed": ["KHR_lights_punctual"],
  "extensions": {"KHR_lights_punctual": {"lights": [
    {"type": "directional", "color": [1, 0.5, 0.25], "intensity": 2},
    {"type": "spot", "range": 5, "spot": {"innerConeAngle": 0.25, "outerConeAngle": 0.5}}]}},)");
    // Node 3 (the camera node, turned 90 degrees about +y) also carries light 0; node 2 light 1.
    replaceOnce(text, R"({"camera": 0,)", R"({"camera": 0, "extensions": {"KHR_lights_punctual": {"light": 0}},)");
    replaceOnce(text, R"({"mesh": 0, "scale": [-1, 1, 1]})",
                R"({"mesh": 0, "scale": [-1, 1, 1], "extensions": {"KHR_lights_punctual": {"light": 1}}})");
    std::vector<std::string> warnings;
    const GltfScene scene = loadGltf(write("cuberille-lights.gltf", text), [&](const std::string& w) { warnings.push_back(w); });
    ASSERT_EQ(scene.lights.size(), 2u);
    for (const auto& w : warnings)
        EXPECT_EQ(w.find(" light"), std::string::npos) << "unexpected warning: " << w;
    // Node order: node 2 (the spot) comes before node 3 (the camera node with the sun).
    const raster::Light& spot = scene.lights[0];
    EXPECT_EQ(spot.type, raster::LightType::Spot);
    EXPECT_FLOAT_EQ(spot.range, 5.0f);
    EXPECT_FLOAT_EQ(spot.cosInnerCone, std::cos(0.25f));
    EXPECT_FLOAT_EQ(spot.cosOuterCone, std::cos(0.5f));
    EXPECT_NEAR(glm::length(spot.intensity), glm::length(glm::vec3(1.0f / float(M_PI))), 1e-6f);
    const raster::Light& sun = scene.lights[1];
    EXPECT_EQ(sun.type, raster::LightType::Directional);
    // The node's -z, turned 90 degrees about +y, is world -x: the light travels towards -x.
    EXPECT_NEAR(glm::distance(sun.direction, glm::vec3(-1, 0, 0)), 0.0f, 1e-5f);
    // glTF's lux for a BRDF with albedo / pi; ours folds the pi into the light.
    EXPECT_NEAR(glm::distance(sun.intensity, glm::vec3(2, 1, 0.5f) / float(M_PI)), 0.0f, 1e-6f);
}

TEST(GltfLoader, AccessorPastItsBufferIsAnInputError) {
    try {
        loadGltf(write("cuberille-bad-accessor.gltf", gltf("400")), [](const std::string&) {});
        ADD_FAILURE() << "accepted an accessor larger than its buffer view";
    } catch (const InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("cuberille-bad-accessor.gltf"), std::string::npos) << what;
        EXPECT_NE(what.find("accessor 0"), std::string::npos) << what;
    }
}

TEST(GltfLoader, TruncatedOrMissingFilesAreInputErrors) {
    const std::string full = gltf();
    for (size_t length : {size_t(0), size_t(10), full.size() / 2, full.size() - 3}) {
        const fs::path p = write("cuberille-cut.gltf", full.substr(0, length));
        EXPECT_THROW(loadGltf(p, [](const std::string&) {}), InputError) << length;
    }
    EXPECT_THROW(loadGltf("/nonexistent/model.glb", [](const std::string&) {}), InputError);
    const fs::path glb = write("cuberille-cut.glb", std::string("glTF\x02\0\0\0", 8));
    EXPECT_THROW(loadGltf(glb, [](const std::string&) {}), InputError);
}

}  // namespace

// glTF as exporters write it (issue 29): sparse accessors, quantized attributes
// (KHR_mesh_quantization), required and merely used extensions, KHR_materials_emissive_strength.

namespace {

// A quad of two triangles whose POSITION accessor `positions` the caller made; one node, one mesh.
std::filesystem::path writeQuad(testing::GltfBuilder& b, int positions, const std::string& name,
                                const nlohmann::json& material = nullptr) {
    nlohmann::json primitive = {{"attributes", {{"POSITION", positions}}}, {"indices", b.indices({0, 1, 2, 0, 2, 3})}};
    if (!material.is_null()) primitive["material"] = b.push("materials", material);
    b.push("nodes", {{"mesh", b.push("meshes", {{"primitives", {primitive}}})}});
    b.json()["scenes"] = {{{"nodes", {0}}}};
    b.json()["scene"] = 0;
    const std::filesystem::path path = testing::uniqueTempPath(name + ".gltf");
    b.write(path);
    return path;
}

const std::vector<glm::vec3> kQuad = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};

}  // namespace

TEST(GltfLoader, SparseAccessorsReadAsTheirDenseEquivalent) {
    for (bool withBase : {true, false}) {
        testing::GltfBuilder b;
        // Base: the quad moved to z = 5 (or no base: zeros); sparse: vertices 1 and 3 replaced.
        std::vector<glm::vec3> base = kQuad;
        for (glm::vec3& p : base) p.z = 5.0f;
        const int accessor = b.positions(base);
        nlohmann::json& a = b.json()["accessors"][size_t(accessor)];
        if (!withBase) a.erase("bufferView");
        const std::vector<uint16_t> indices = {1, 3};
        const std::vector<float> values = {2, 0, 0, 0, 2, 0};
        a["sparse"] = {{"count", 2},
                       {"indices", {{"bufferView", b.view(indices.data(), 4)}, {"componentType", 5123}}},
                       {"values", {{"bufferView", b.view(values.data(), 24)}}}};
        a["min"] = {0, 0, 0}, a["max"] = {2, 2, 5};
        const GltfScene s = loadGltf(writeQuad(b, accessor, withBase ? "sparse-base" : "sparse-zeros"), [](const std::string&) {});
        ASSERT_EQ(s.meshes.size(), 1u);
        const std::vector<glm::vec3> expected = withBase ? std::vector<glm::vec3>{{0, 0, 5}, {2, 0, 0}, {1, 1, 5}, {0, 2, 0}}
                                                         : std::vector<glm::vec3>{{0, 0, 0}, {2, 0, 0}, {0, 0, 0}, {0, 2, 0}};
        EXPECT_EQ(s.meshes[0].positions, expected) << "with base " << withBase;
    }
    // An index past the count, or out of order, is bad input naming the accessor.
    testing::GltfBuilder b;
    const int accessor = b.positions(kQuad);
    const std::vector<uint16_t> indices = {2, 7};
    const std::vector<float> values(6, 1.0f);
    b.json()["accessors"][size_t(accessor)]["sparse"] = {
        {"count", 2},
        {"indices", {{"bufferView", b.view(indices.data(), 4)}, {"componentType", 5123}}},
        {"values", {{"bufferView", b.view(values.data(), 24)}}}};
    try {
        loadGltf(writeQuad(b, accessor, "sparse-bad"), [](const std::string&) {});
        FAIL() << "a sparse index past the count was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("accessor 0: sparse index 7 is past its 4 elements"), std::string::npos) << e.what();
    }
}

// KHR_mesh_quantization: positions as normalised shorts (32767 is 1), padded to 8-byte strides, as
// gltfpack writes them (it then scales them back through the node's transform).
TEST(GltfLoader, QuantizedPositionsReadAsTheirNormalisedValues) {
    testing::GltfBuilder b;
    const std::vector<int16_t> quantized = {0, 0, 0, 0, 32767, 0, 0, 0, 32767, 32767, 0, 0, 0, 32767, 0, 0};
    const int accessor = b.push("accessors", {{"bufferView", b.view(quantized.data(), quantized.size() * 2)},
                                              {"componentType", 5122}, {"normalized", true}, {"count", 4}, {"type", "VEC3"},
                                              {"byteOffset", 0}, {"min", {0, 0, 0}}, {"max", {1, 1, 0}}});
    b.json()["bufferViews"][b.json()["bufferViews"].size() - 1]["byteStride"] = 8;  // 3 shorts and padding
    b.json()["extensionsUsed"] = {"KHR_mesh_quantization"};
    b.json()["extensionsRequired"] = {"KHR_mesh_quantization"};
    const std::filesystem::path path = writeQuad(b, accessor, "quantized");
    std::vector<std::string> warnings;
    const GltfScene s = loadGltf(path, [&](const std::string& w) { warnings.push_back(w); });
    EXPECT_TRUE(warnings.empty()) << warnings.front();
    ASSERT_EQ(s.meshes.size(), 1u);
    EXPECT_EQ(s.meshes[0].positions, kQuad);
}

// glTF 2.0 §3.7.2.1 allows unsigned byte, short and int scalars as indices. Any other kind —
// signed bytes whose elements are one byte long were a heap overflow found by fuzz_gltf — is bad
// input naming the accessor, for each kind, with the elements sized exactly to the buffer view's end.
TEST(GltfLoader, IndicesOfAnyKindButUnsignedScalarsAreRefused) {
    const std::vector<std::pair<int, std::string>> kinds = {
        {5120, "SCALAR"}, {5122, "SCALAR"}, {5126, "SCALAR"}, {5121, "VEC2"}, {5123, "VEC3"}, {5125, "MAT4"}};
    for (const auto& [componentType, type] : kinds) {
        testing::GltfBuilder b;
        const int positions = b.positions(kQuad);
        const size_t componentBytes = componentType == 5120 || componentType == 5121 ? 1
                                      : componentType == 5122 || componentType == 5123 ? 2 : 4;
        const size_t components = type == "SCALAR" ? 1 : type == "VEC2" ? 2 : type == "VEC3" ? 3 : 16;
        const std::vector<uint8_t> zeros(6 * componentBytes * components, 0);
        const int indices = b.push("accessors", {{"bufferView", b.view(zeros.data(), zeros.size())},
                                                 {"componentType", componentType}, {"count", 6}, {"type", type}});
        const nlohmann::json primitive = {{"attributes", {{"POSITION", positions}}}, {"indices", indices}};
        b.push("nodes", {{"mesh", b.push("meshes", {{"primitives", {primitive}}})}});
        b.json()["scenes"] = {{{"nodes", {0}}}};
        b.json()["scene"] = 0;
        const std::filesystem::path path = testing::uniqueTempPath("signed-indices.gltf");
        b.write(path);
        try {
            loadGltf(path, [](const std::string&) {});
            ADD_FAILURE() << "indices of component type " << componentType << " " << type << " were accepted";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find("accessor 1: indices must be unsigned byte, short or int scalars"), std::string::npos)
                << componentType << " " << type << ": " << what;
            EXPECT_NE(what.find(path.filename().string()), std::string::npos) << what;
        }
    }
}

TEST(GltfLoader, ARequiredExtensionItCannotReadIsRefusedAndAUsedOneWarnsOnce) {
    testing::GltfBuilder b;
    const int accessor = b.positions(kQuad);
    b.json()["extensionsUsed"] = {"EXT_mesh_gpu_instancing", "KHR_texture_basisu"};
    b.json()["extensionsRequired"] = {"EXT_mesh_gpu_instancing", "KHR_texture_basisu"};
    const std::filesystem::path required = writeQuad(b, accessor, "required");
    try {
        loadGltf(required, [](const std::string&) {});
        FAIL() << "a file requiring instancing and Basis textures was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(": requires EXT_mesh_gpu_instancing, KHR_texture_basisu, which Cuberille "
                                             "cannot read yet"),
                  std::string::npos) << e.what();
    }
    testing::GltfBuilder used;
    const int usedAccessor = used.positions(kQuad);
    used.json()["extensionsUsed"] = {"KHR_materials_iridescence"};
    std::vector<std::string> warnings;
    const GltfScene s = loadGltf(writeQuad(used, usedAccessor, "used"), [&](const std::string& w) { warnings.push_back(w); });
    EXPECT_EQ(s.meshes.size(), 1u);
    ASSERT_EQ(warnings.size(), 1u);
    EXPECT_NE(warnings[0].find("extension KHR_materials_iridescence is not supported yet and was ignored"), std::string::npos);
}

TEST(GltfLoader, EmissiveStrengthScalesTheEmissiveFactor) {
    testing::GltfBuilder b;
    const int accessor = b.positions(kQuad);
    b.json()["extensionsUsed"] = {"KHR_materials_emissive_strength"};
    const GltfScene s = loadGltf(writeQuad(b, accessor, "emissive-strength",
                                           {{"emissiveFactor", {1.0, 0.5, 0.25}},
                                            {"extensions", {{"KHR_materials_emissive_strength", {{"emissiveStrength", 4.0}}}}}}),
                                 [](const std::string& w) { ADD_FAILURE() << w; });
    ASSERT_EQ(s.meshes.size(), 1u);
    EXPECT_EQ(s.meshes[0].emissive, glm::vec3(4.0f, 2.0f, 1.0f));
}

TEST(GltfLoader, IorSetsTheDielectricReflectanceAndABadOneIsRefused) {
    EXPECT_EQ(dielectricReflectance(1.5f), 0.04f) << "glTF's default: the BRDF's fixed value before the extension";
    EXPECT_EQ(dielectricReflectance(0.0f), 1.0f);
    for (const auto& [ior, good] : {std::pair{1.33, true}, {2.42, true}, {0.0, true}, {0.5, false}, {-1.0, false}}) {
        testing::GltfBuilder b;
        const int accessor = b.positions(kQuad);
        b.json()["extensionsUsed"] = {"KHR_materials_ior"};
        const auto path = writeQuad(b, accessor, "ior", {{"extensions", {{"KHR_materials_ior", {{"ior", ior}}}}}});
        if (!good) {
            EXPECT_THROW(loadGltf(path, [](const std::string&) {}), InputError) << ior;
            continue;
        }
        const GltfScene s = loadGltf(path, [](const std::string& w) { ADD_FAILURE() << w; });
        ASSERT_EQ(s.meshes.size(), 1u);
        EXPECT_EQ(s.meshes[0].ior, float(ior));
    }
    testing::GltfBuilder b;  // without the extension: glTF's 1.5
    const GltfScene plain = loadGltf(writeQuad(b, b.positions(kQuad), "no-ior"), [](const std::string&) {});
    EXPECT_EQ(plain.meshes[0].ior, 1.5f);
}

}  // namespace cuberille::scene
