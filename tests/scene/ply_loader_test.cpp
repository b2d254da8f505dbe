// PLY: the three encodings give the same mesh; polygons become fans; triangle strips give the
// triangles of the same mesh's face list; unknown elements and properties are skipped; every
// truncation and corrupt count is a clear InputError.

#include <gtest/gtest.h>

#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>

#include <zlib.h>

#include "scene/input_error.h"
#include "scene/ply_loader.h"
#include "tests/scene/ply_builder.h"
#include "tests/temp_paths.h"

namespace cuberille::scene {
namespace {

// A square pyramid: 5 vertices with colours, one quad base (a fan of 2) and 4 triangles, plus
// an unrelated element and property the reader must skip.
const float kPositions[5][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}, {0.5f, 0.5f, 1}};
const std::vector<std::vector<int>> kFaces = {{0, 3, 2, 1}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}, {3, 0, 4}};

std::string header(const std::string& format) {
    return "ply\nformat " + format + " 1.0\ncomment made by a test\n"
           "element vertex 5\nproperty float x\nproperty float y\nproperty float z\n"
           "property uchar red\nproperty uchar green\nproperty uchar blue\nproperty short extra\n"
           "element face 5\nproperty list uchar int vertex_indices\n"
           "element edge 1\nproperty int a\nproperty int b\nend_header\n";
}

std::string asciiPly() {
    std::string s = header("ascii");
    for (int i = 0; i < 5; ++i)
        s += std::to_string(kPositions[i][0]) + " " + std::to_string(kPositions[i][1]) + " " +
             std::to_string(kPositions[i][2]) + " 255 128 0 -7\n";
    for (const auto& f : kFaces) {
        s += std::to_string(f.size());
        for (int v : f) s += " " + std::to_string(v);
        s += "\n";
    }
    return s + "0 1\n";
}

template <class T>
void put(std::string& s, T value, bool bigEndian) {
    char b[sizeof(T)];
    std::memcpy(b, &value, sizeof(T));
    if (bigEndian == (std::endian::native == std::endian::little)) std::reverse(b, b + sizeof(T));
    s.append(b, sizeof(T));
}

std::string binaryPly(bool bigEndian) {
    std::string s = header(bigEndian ? "binary_big_endian" : "binary_little_endian");
    for (int i = 0; i < 5; ++i) {
        for (int k = 0; k < 3; ++k) put(s, kPositions[i][k], bigEndian);
        put<uint8_t>(s, 255, bigEndian), put<uint8_t>(s, 128, bigEndian), put<uint8_t>(s, 0, bigEndian);
        put<int16_t>(s, -7, bigEndian);
    }
    for (const auto& f : kFaces) {
        put<uint8_t>(s, uint8_t(f.size()), bigEndian);
        for (int v : f) put<int32_t>(s, v, bigEndian);
    }
    put<int32_t>(s, 0, bigEndian), put<int32_t>(s, 1, bigEndian);
    return s;
}

void expectPyramid(const Mesh& m) {
    ASSERT_EQ(m.positions.size(), 5u);
    for (int i = 0; i < 5; ++i)
        EXPECT_EQ(m.positions[i], glm::vec3(kPositions[i][0], kPositions[i][1], kPositions[i][2]));
    const std::vector<uint32_t> expected = {0, 3, 2, 0, 2, 1, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
    EXPECT_EQ(m.indices, expected);
    ASSERT_EQ(m.colors.size(), 5u);
    EXPECT_FLOAT_EQ(m.colors[0].r, 1.0f);
    EXPECT_NEAR(m.colors[0].g, 0.2158f, 1e-3f);  // sRGB 128/255 decoded to linear
    EXPECT_EQ(m.normals.size(), 5u);              // computed: the file has none
    EXPECT_NEAR(glm::length(m.normals[4]), 1.0f, 1e-5f);
}

TEST(PlyLoader, AsciiAndBothBinaryEndiannessesGiveTheSameMesh) {
    expectPyramid(parsePly(asciiPly(), "a.ply"));
    expectPyramid(parsePly(binaryPly(false), "le.ply"));
    expectPyramid(parsePly(binaryPly(true), "be.ply"));
}

TEST(PlyLoader, ReadsGzipCompressedFiles) {
    const auto path = cuberille::testing::uniqueTempPath("pyramid.ply.gz");
    const std::string bytes = binaryPly(false);
    gzFile f = gzopen(path.string().c_str(), "wb");
    ASSERT_NE(f, nullptr);
    gzwrite(f, bytes.data(), unsigned(bytes.size()));
    gzclose(f);
    expectPyramid(loadPly(path));
    std::filesystem::remove(path);
}

/// gzip's bytes for `data`, as one member, compressed by zlib.
std::string gzipMember(const std::string& data) {
    z_stream z{};
    deflateInit2(&z, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY);  // +16: a gzip wrapper
    std::string out(deflateBound(&z, uLong(data.size())) + 64, '\0');
    z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
    z.avail_in = uInt(data.size());
    z.next_out = reinterpret_cast<Bytef*>(out.data());
    z.avail_out = uInt(out.size());
    deflate(&z, Z_FINISH);
    out.resize(z.total_out);
    deflateEnd(&z);
    return out;
}

/// What zlib's gzread makes of a file (the slow, sure reference), or nothing when it fails.
std::optional<std::string> zlibReads(const std::filesystem::path& path) {
    gzFile f = gzopen(path.string().c_str(), "rb");
    std::string out;
    char buffer[4096];
    int n;
    while ((n = gzread(f, buffer, sizeof buffer)) > 0) out.append(buffer, size_t(n));
    int error = Z_OK;
    gzerror(f, &error);
    gzclose(f);
    if (n < 0 || (error != Z_OK && error != Z_STREAM_END)) return std::nullopt;
    return out;
}

// Every shape a .gz file takes, read as zlib reads it: one member, several (the last smaller
// than the first, so its size trailer undersizes the first's buffer; one empty), a file of more
// than 64 KiB, trailing bytes that are not a member, bytes that are not gzip at all, and damage
// (a cut, a flipped byte) that both must refuse — here with an InputError naming the file.
TEST(PlyLoader, GzipFilesReadAsZlibReadsThem) {
    std::string large;
    for (uint32_t i = 0; i < 300000; ++i) large += char('a' + (i * 7919u) % 26u);
    const std::string a = "first member, " + large, b = "second", c;
    const std::vector<std::pair<std::string, std::string>> files = {
        {"one", gzipMember(a)},
        {"three", gzipMember(a) + gzipMember(c) + gzipMember(b)},
        {"trailing", gzipMember(b) + "not a member"},
        {"plain", "ply\nformat ascii 1.0\n"},
        {"cut", gzipMember(a).substr(0, 2000)},
        {"flipped", [&] { std::string g = gzipMember(a); g[g.size() / 2] ^= 0x5a; return g; }()},
    };
    for (const auto& [name, bytes] : files) {
        const auto path = cuberille::testing::uniqueTempPath(name + ".ply.gz");
        std::ofstream(path, std::ios::binary) << bytes;
        const std::optional<std::string> expected = zlibReads(path);
        try {
            const std::string got = readFileBytes(path);
            ASSERT_TRUE(expected.has_value()) << name << ": zlib refuses it, we read " << got.size() << " bytes";
            EXPECT_EQ(got, *expected) << name;
        } catch (const InputError& e) {
            EXPECT_FALSE(expected.has_value()) << name << ": " << e.what();
            EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
        }
        std::filesystem::remove(path);
    }
}

std::string layoutPly(bool bigEndian, const std::string& positionType, bool normals, bool colors,
                      const std::string& countType, const std::string& indexType);

TEST(PlyLoader, EveryTruncationIsAnInputErrorNamingTheFile) {
    // The pyramid, and a layout every fast path of the binary reader takes.
    for (const std::string& full : {binaryPly(false), binaryPly(true), asciiPly(),
                                    layoutPly(false, "float", false, false, "uchar", "int")}) {
        const size_t body = full.find("end_header\n") + 11;
        for (size_t length = 0; length < full.size(); ++length) {
            // ASCII may legally end after the last face line's digits; every binary cut may not.
            try {
                parsePly(std::string_view(full).substr(0, length), "cut.ply");
                if (length < body || full.find("binary") != std::string::npos)
                    ADD_FAILURE() << "accepted a file cut at " << length << " of " << full.size();
            } catch (const InputError& e) {
                EXPECT_EQ(std::string(e.what()).rfind("cut.ply: ", 0), 0u) << e.what();
            }
        }
    }
}

TEST(PlyLoader, CorruptCountsAndIndicesAreReportedBeforeUse) {
    std::string huge = binaryPly(false);
    huge.replace(huge.find("element vertex 5"), 16, "element vertex 999999999999");
    EXPECT_THROW(
        {
            try {
                parsePly(huge, "huge.ply");
            } catch (const InputError& e) {
                EXPECT_NE(std::string(e.what()).find("cannot fit"), std::string::npos) << e.what();
                throw;
            }
        },
        InputError);

    std::string badIndex = asciiPly();
    badIndex.replace(badIndex.find("3 0 1 4"), 7, "3 0 1 9");
    try {
        parsePly(badIndex, "bad.ply");
        ADD_FAILURE() << "accepted an out-of-range index";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "bad.ply: face 1: vertex index 9 is out of range (5 vertices)");
    }
    EXPECT_THROW(parsePly("plx\n", "magic.ply"), InputError);
    EXPECT_THROW(parsePly("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n1\n", "noy.ply"),
                 InputError);
}

TEST(PlyLoader, ASecondVertexElementIsRefused) {
    // Found by fuzz_ply: a second vertex element without colours read the first one's colour
    // property index.
    const std::string twice = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
                              "property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
                              "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n"
                              "0 0 0 255 0 0\n1 1 1\n";
    try {
        parsePly(twice, "twice.ply");
        ADD_FAILURE() << "accepted two vertex elements";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("twice.ply: element 'vertex': a second vertex element"), std::string::npos)
            << e.what();
    }
}

// A binary PLY of the given vertex and index types, in either byte order: a 5x5 grid of
// vertices at multiples of 1/8 (exact in every type) and its 32 triangles, with a quad and a
// pentagon among them, and a strip when `strips`.
std::string layoutPly(bool bigEndian, const std::string& positionType, bool normals, bool colors,
                      const std::string& countType, const std::string& indexType) {
    std::string s = "ply\nformat " + std::string(bigEndian ? "binary_big_endian" : "binary_little_endian") + " 1.0\n";
    s += "element vertex 25\nproperty " + positionType + " x\nproperty " + positionType + " y\nproperty " + positionType + " z\n";
    if (normals) s += "property float nx\nproperty float ny\nproperty float nz\n";
    if (colors) s += "property uchar red\nproperty uchar green\nproperty uchar blue\n";
    s += "element face 3\nproperty list " + countType + " " + indexType + " vertex_indices\n";
    s += "element tristrips 1\nproperty list " + countType + " " + indexType + " vertex_indices\nend_header\n";
    auto value = [&](const std::string& type, double v) {
        if (type == "float") put(s, float(v), bigEndian);
        else if (type == "double") put(s, v, bigEndian);
        else if (type == "uchar") put(s, uint8_t(v), bigEndian);
        else if (type == "ushort") put(s, uint16_t(v), bigEndian);
        else if (type == "int") put(s, int32_t(v), bigEndian);
        else put(s, uint32_t(v), bigEndian);
    };
    for (int i = 0; i < 25; ++i) {
        for (double v : {(i % 5) / 8.0, (i / 5) / 8.0, ((i * 7) % 3) / 8.0}) value(positionType, v);
        if (normals) for (double v : {0.0, 0.0, 1.0}) value("float", v);
        if (colors) for (double v : {double(i * 10), 128.0, 255.0 - i}) value("uchar", v);
    }
    const std::vector<std::vector<double>> faces = {{0, 1, 6}, {1, 2, 7, 6}, {2, 3, 8, 13, 12}};
    for (const auto& f : faces) {
        value(countType, double(f.size()));
        for (double v : f) value(indexType, v);
    }
    std::vector<double> strip = {5, 10, 6, 11, 7, 12};
    if (indexType == "int") strip.insert(strip.end(), {-1, 15, 20, 16, 21});
    value(countType, double(strip.size()));
    for (double v : strip) value(indexType, v);
    return s;
}

TEST(PlyLoader, TheFastAndTheGeneralReaderGiveTheSameMeshForEveryLayout) {
    // Little-endian files take the binary fast paths where their layout allows (native floats,
    // 32-bit indices, uchar counts); big-endian ones always the general reader.
    int layouts = 0;
    for (const char* positionType : {"float", "double"})
        for (bool normals : {false, true})
            for (bool colors : {false, true})
                for (const char* countType : {"uchar", "int"})
                    for (const char* indexType : {"int", "uint", "ushort"}) {
                        const Mesh fast = parsePly(layoutPly(false, positionType, normals, colors, countType, indexType), "le.ply");
                        const Mesh general = parsePly(layoutPly(true, positionType, normals, colors, countType, indexType), "be.ply");
                        const std::string layout = std::string(positionType) + (normals ? " normals" : "") +
                                                   (colors ? " colours" : "") + " " + countType + " " + indexType;
                        EXPECT_EQ(fast.positions, general.positions) << layout;
                        EXPECT_EQ(fast.normals, general.normals) << layout;
                        EXPECT_EQ(fast.colors, general.colors) << layout;
                        EXPECT_EQ(fast.indices, general.indices) << layout;
                        EXPECT_EQ(fast.triangleCount(), size_t(1 + 2 + 3 + (std::string(indexType) == "int" ? 4 + 2 : 4))) << layout;
                        ++layouts;
                    }
    EXPECT_EQ(layouts, 48);
}

TEST(PlyLoader, EveryStripVariantGivesTheTrianglesOfTheFaceList) {
    using testing::PlyConnectivity;
    const testing::PlyGrid grid;
    for (bool binary : {false, true}) {
        const Mesh faces = parsePly(grid.ply(PlyConnectivity::FaceList, binary), "faces.ply");
        ASSERT_EQ(faces.indices.size(), size_t(grid.rows * grid.columns * 6));
        for (PlyConnectivity kind : {PlyConnectivity::StripsWithRestarts, PlyConnectivity::StripPerInstance,
                                     PlyConnectivity::StitchedStrip}) {
            const Mesh strips = parsePly(grid.ply(kind, binary), "strips.ply");
            // The same triangles, each with the same first vertex and winding, in the same order.
            EXPECT_EQ(strips.indices, faces.indices) << "variant " << int(kind) << (binary ? " binary" : " ascii");
            EXPECT_EQ(strips.positions, faces.positions);
            EXPECT_EQ(strips.normals, faces.normals);
        }
    }
}

TEST(PlyLoader, StripWindingAlternatesAndRestartsResetIt) {
    // Every triangle of a flat strip faces the same way: its signed area in the plane keeps the
    // sign of the strip's first triangle, also after a restart at an odd place.
    const std::string ply = "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n"
                            "property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n"
                            "0 0 0\n0 1 0\n1 0 0\n1 1 0\n2 0 0\n2 1 0\n"
                            "10 0 1 2 3 4 -1 2 3 4 5\n";
    const Mesh m = parsePly(ply, "zigzag.ply");
    ASSERT_EQ(m.indices.size(), 5u * 3u);  // 3 from the first strip, 2 from the second
    for (size_t t = 0; t < m.indices.size(); t += 3) {
        const glm::vec3 a = m.positions[m.indices[t]], b = m.positions[m.indices[t + 1]], c = m.positions[m.indices[t + 2]];
        const float area = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        EXPECT_LT(area, 0.0f) << "triangle " << t / 3;
    }
    const std::vector<uint32_t> expected = {0, 1, 2, 2, 1, 3, 2, 3, 4, 2, 3, 4, 4, 3, 5};
    EXPECT_EQ(m.indices, expected);
}

TEST(PlyLoader, StripJoinsWithoutAreaAreDroppedAndBadStripIndicesRefused) {
    const std::string head = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                             "property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n"
                             "0 0 0\n0 1 0\n1 0 0\n1 1 0\n";
    EXPECT_EQ(parsePly(head + "6 0 1 1 2 2 3\n", "joins.ply").indices.size(), 0u);  // every triangle repeats a vertex
    EXPECT_EQ(parsePly(head + "2 -1 -1\n", "empty.ply").indices.size(), 0u);
    try {
        parsePly(head + "4 0 1 -2 3\n", "bad.ply");
        ADD_FAILURE() << "accepted -2 in a strip";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "bad.ply: tristrips 0: vertex index -2 is out of range (4 vertices)");
    }
    try {  // -1 restarts strips only; in a face it is an index out of range
        parsePly("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                 "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n0 1 0\n1 0 0\n3 0 -1 2\n",
                 "face.ply");
        ADD_FAILURE() << "accepted -1 in a face";
    } catch (const InputError& e) {
        EXPECT_STREQ(e.what(), "face.ply: face 0: vertex index -1 is out of range (3 vertices)");
    }
}

TEST(PlyLoader, AListLongerThanAMillionIsReadWhenTheFileHoldsIt) {
    // One tristrips instance holds a whole scan's strips: 1.2M indices of a strip over 4 vertices.
    std::string ply = "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                      "property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n";
    const float corners[4][3] = {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 1, 0}};
    ply.append(reinterpret_cast<const char*>(corners), sizeof corners);
    const int32_t count = 1200000;
    ply.append(reinterpret_cast<const char*>(&count), 4);
    for (int32_t i = 0; i < count; ++i) {
        const int32_t v = i % 4 == 3 ? -1 : i % 4;  // 0 1 2 -1: one triangle a group
        ply.append(reinterpret_cast<const char*>(&v), 4);
    }
    EXPECT_EQ(parsePly(ply, "long.ply").indices.size(), size_t(count / 4) * 3);
    std::string cut = ply.substr(0, ply.size() - 4);
    try {
        parsePly(cut, "cut.ply");
        ADD_FAILURE() << "accepted a list longer than the file";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("cannot fit"), std::string::npos) << e.what();
    }
}

}  // namespace
}  // namespace cuberille::scene
