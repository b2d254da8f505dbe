// Writes the seed corpora of the fuzz targets (fuzz/corpus/TARGET/), made in code like the tests'
// data: small valid files of every format, so the fuzzers start from inputs that reach deep.
//
//   make_seeds OUTPUT_DIR

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <draco/compression/encode.h>
#include <draco/mesh/triangle_soup_mesh_builder.h>
#include <meshoptimizer.h>

#include "lod/lod_pyramid.h"
#include "lod/pyramid_ranges.h"
#include "voxel/cvox_file.h"
#include "voxel/partial_voxelization_file.h"
#include "voxel/geometry_stream.h"
#include "voxel/mesh_view.h"
#include "voxel/octree_voxelizer.h"

namespace {

namespace fs = std::filesystem;
using namespace cuberille;

void put(const fs::path& dir, const std::string& target, const std::string& name, const std::string& bytes) {
    fs::create_directories(dir / target);
    std::ofstream(dir / target / name, std::ios::binary) << bytes;
}

std::string u32(uint32_t v) { return std::string(reinterpret_cast<const char*>(&v), 4); }

const char* kTetrahedronObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";

// `materials`: a "materials" array the primitive's material 0 comes from; empty: none.
std::string triangleGlb(const std::string& materials = "") {
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const std::string bin(reinterpret_cast<const char*>(p), sizeof p);
    std::string json = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0,"children":[1]},{"mesh":0,"translation":[1,0,0]}],)" +
                       (materials.empty() ? std::string(R"("meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],)")
                                          : R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"material":0}]}],"materials":)" + materials + ",") +
                       R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],)"
                       R"("bufferViews":[{"buffer":0,"byteLength":36}],"buffers":[{"byteLength":36}]})";
    while (json.size() % 4) json += ' ';
    return "glTF" + u32(2) + u32(uint32_t(12 + 8 + json.size() + 8 + bin.size())) + u32(uint32_t(json.size())) + "JSON" +
           json + u32(uint32_t(bin.size())) + std::string("BIN\0", 4) + bin;
}

// The same triangle with its positions and indices in EXT_meshopt_compression streams, read
// through a fallback buffer without data, as gltfpack writes them: the fuzzer reaches the decoders.
std::string meshoptTriangleGlb() {
    const float p[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const unsigned int indices[3] = {0, 1, 2};
    std::string positions(meshopt_encodeVertexBufferBound(3, 12), '\0'), triangles(meshopt_encodeIndexBufferBound(3, 3), '\0');
    positions.resize(meshopt_encodeVertexBuffer(reinterpret_cast<unsigned char*>(positions.data()), positions.size(), p, 3, 12));
    triangles.resize(meshopt_encodeIndexBuffer(reinterpret_cast<unsigned char*>(triangles.data()), triangles.size(), indices, 3));
    while (positions.size() % 4) positions += '\0';
    std::string bin = positions + triangles;
    while (bin.size() % 4) bin += '\0';
    auto stream = [](size_t offset, size_t length, int stride, const char* mode) {
        return R"({"EXT_meshopt_compression":{"buffer":0,"byteOffset":)" + std::to_string(offset) + R"(,"byteLength":)" +
               std::to_string(length) + R"(,"byteStride":)" + std::to_string(stride) + R"(,"count":3,"mode":")" + mode + "\"}}";
    };
    std::string json = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
                       R"("extensionsUsed":["EXT_meshopt_compression"],"extensionsRequired":["EXT_meshopt_compression"],)"
                       R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1}]}],)"
                       R"("accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},)"
                       R"({"bufferView":1,"componentType":5123,"count":3,"type":"SCALAR"}],)"
                       R"("bufferViews":[{"buffer":1,"byteLength":36,"byteStride":12,"extensions":)" +
                       stream(0, positions.size(), 12, "ATTRIBUTES") + R"(},{"buffer":1,"byteOffset":36,"byteLength":6,"extensions":)" +
                       stream(positions.size(), triangles.size(), 2, "TRIANGLES") + R"(}],)" + R"("buffers":[{"byteLength":)" +
                       std::to_string(bin.size()) + R"(},{"byteLength":44,"extensions":{"EXT_meshopt_compression":{"fallback":true}}}]})";
    while (json.size() % 4) json += ' ';
    return "glTF" + u32(2) + u32(uint32_t(12 + 8 + json.size() + 8 + bin.size())) + u32(uint32_t(json.size())) + "JSON" +
           json + u32(uint32_t(bin.size())) + std::string("BIN\0", 4) + bin;
}

// The triangle as a KHR_draco_mesh_compression primitive: accessors without views, the Draco
// stream in the BIN chunk.
std::string dracoTriangleGlb() {
    const float p[3][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    draco::TriangleSoupMeshBuilder builder;
    builder.Start(1);
    const int position = builder.AddAttribute(draco::GeometryAttribute::POSITION, 3, draco::DT_FLOAT32);
    builder.SetAttributeValuesForFace(position, draco::FaceIndex(0), p[0], p[1], p[2]);
    const std::unique_ptr<draco::Mesh> mesh = builder.Finalize();
    draco::Encoder encoder;
    draco::EncoderBuffer encoded;
    if (!encoder.EncodeMeshToBuffer(*mesh, &encoded).ok()) return {};
    std::string bin(encoded.data(), encoded.size());
    const size_t streamBytes = bin.size();
    while (bin.size() % 4) bin += '\0';
    std::string json = R"({"asset":{"version":"2.0"},"scene":0,"scenes":[{"nodes":[0]}],"nodes":[{"mesh":0}],)"
                       R"("extensionsUsed":["KHR_draco_mesh_compression"],"extensionsRequired":["KHR_draco_mesh_compression"],)"
                       R"("meshes":[{"primitives":[{"attributes":{"POSITION":0},"indices":1,"extensions":{"KHR_draco_mesh_compression":)"
                       R"({"bufferView":0,"attributes":{"POSITION":)" + std::to_string(mesh->attribute(position)->unique_id()) + R"(}}}}]}],)"
                       R"("accessors":[{"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},)"
                       R"({"componentType":5123,"count":3,"type":"SCALAR"}],)"
                       R"("bufferViews":[{"buffer":0,"byteLength":)" + std::to_string(streamBytes) + R"(}],)" +
                       R"("buffers":[{"byteLength":)" + std::to_string(bin.size()) + "}]}";
    while (json.size() % 4) json += ' ';
    return "glTF" + u32(2) + u32(uint32_t(12 + 8 + json.size() + 8 + bin.size())) + u32(uint32_t(json.size())) + "JSON" +
           json + u32(uint32_t(bin.size())) + std::string("BIN\0", 4) + bin;
}

std::string binaryPly() {
    std::string s = "ply\nformat binary_little_endian 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
                    "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
    const float v[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    s.append(reinterpret_cast<const char*>(v), sizeof v);
    const int32_t faces[2][3] = {{0, 2, 1}, {0, 1, 3}};
    for (const auto& f : faces) {
        s += char(3);
        s.append(reinterpret_cast<const char*>(f), 12);
    }
    return s;
}

std::unique_ptr<voxel::MeshView> tetrahedron() {
    return voxel::openMeshView(fs::temp_directory_path() / "cuberille-seed-tet.obj", nullptr);
}

}  // namespace

/// A 16 x 8 equirectangular Radiance file: run-length scanlines (a run and a literal per channel)
/// or flat pixels.
std::string radianceHdr(bool runLength) {
    std::string hdr = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\nEXPOSURE=1.0\n\n-Y 8 +X 16\n";
    for (int y = 0; y < 8; ++y) {
        if (!runLength) {
            for (int x = 0; x < 16; ++x) hdr += {char(x * 16), char(y * 32), char(128), char(128 + (x & 3))};
            continue;
        }
        hdr += {char(2), char(2), char(0), char(16)};
        for (int channel = 0; channel < 4; ++channel) {
            hdr += {char(128 + 8), char(channel == 3 ? 129 : 64 + y)};  // a run of 8
            hdr += char(8);                                               // then 8 literal bytes
            for (int x = 0; x < 8; ++x) hdr += char(channel == 3 ? 128 : x * 30);
        }
    }
    return hdr;
}

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: make_seeds OUTPUT_DIR\n");
        return 2;
    }
    const fs::path dir = argv[1];
    put(dir, "fuzz_tri", "two.tri", "# two overlapping triangles\n0 0  10 0  0 10  1 0 0\n2 2  12 3  4 11  0 1 0\n");
    put(dir, "fuzz_tri", "far.tri", "-1e6 -1e6  1e6 -1e6  0 1e6  1 1 1\n");
    put(dir, "fuzz_ply", "ascii.ply",
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 1\n"
        "property list uchar int vertex_indices\nend_header\n0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 0 0 255\n3 0 1 2\n");
    put(dir, "fuzz_ply", "binary.ply", binaryPly());
    put(dir, "fuzz_obj", "tet.obj", kTetrahedronObj);
    put(dir, "fuzz_obj", "materials.obj",
        "mtllib fuzz.mtl\nnewmtl red\nKd 1 0 0\nd 0.5\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\n"
        "usemtl red\nf 1/1/1 2/2/1 3/3/1\ng other\no obj\nf -3 -2 -1\n");
    put(dir, "fuzz_gltf", "two-nodes.glb", triangleGlb());
    // Every material extension the reader honours, in one material: the fuzzer starts inside them.
    put(dir, "fuzz_gltf", "material-extensions.glb",
        triangleGlb(R"([{"emissiveFactor":[1,0.5,0],"extensions":{"KHR_materials_emissive_strength":{"emissiveStrength":2},)"
                    R"("KHR_materials_ior":{"ior":1.7},"KHR_materials_specular":{"specularFactor":0.5,"specularColorFactor":[1,0.9,0.8]},)"
                    R"("KHR_materials_clearcoat":{"clearcoatFactor":1,"clearcoatRoughnessFactor":0.2},)"
                    R"("KHR_materials_sheen":{"sheenColorFactor":[0.8,0.7,0.6],"sheenRoughnessFactor":0.5},)"
                    R"("KHR_materials_transmission":{"transmissionFactor":0.9},)"
                    R"("KHR_materials_volume":{"thicknessFactor":0.5,"attenuationColor":[0.9,0.5,0.2],"attenuationDistance":2}}}])"));
    put(dir, "fuzz_gltf", "meshopt.glb", meshoptTriangleGlb());
    put(dir, "fuzz_gltf", "draco.glb", dracoTriangleGlb());
    put(dir, "fuzz_hdr", "runs.hdr", radianceHdr(true));
    put(dir, "fuzz_hdr", "flat.hdr", radianceHdr(false));
    put(dir, "fuzz_camera_path", "keys.path", "# px py pz tx ty tz\n0 0 3 0 0 0\n1 1 2 0 0 0\n0 2 1 0 0.5 0\n");
    // A 12^3 u8 sphere, after the 8-byte header the fuzz target reads: dims, type, iso.
    {
        std::string raw;
        const uint16_t dims[3] = {12, 12, 12};
        raw.append(reinterpret_cast<const char*>(dims), 6);
        raw += char(0), raw += char(128 * 4 / 4);
        for (int z = 0; z < 12; ++z)
            for (int y = 0; y < 12; ++y)
                for (int x = 0; x < 12; ++x)
                    raw += char((x - 6) * (x - 6) + (y - 6) * (y - 6) + (z - 6) * (z - 6) < 20 ? 200 : 10);
        put(dir, "fuzz_raw_volume", "sphere.raw", raw);
    }
    // .cgs and .cvox of the tetrahedron.
    std::ofstream(fs::temp_directory_path() / "cuberille-seed-tet.obj") << kTetrahedronObj;
    {
        std::ostringstream out;
        voxel::writeGeometryStream(*tetrahedron(), out);
        put(dir, "fuzz_cgs", "tet.cgs", out.str());
    }
    // The reader-only target also gets a small model (two levels, a few blocks), which mutations
    // reach the end of far more often than the 128-cube one.
    for (const int resolution : {128, 16}) {
        voxel::VoxelizeOptions o;
        o.resolution = resolution;
        voxel::VoxelModel m = voxel::voxelizeMesh(*tetrahedron(), o);
        lod::buildLodPyramid(m, {});
        std::ostringstream out;
        voxel::writeCvox(m, out);
        const std::string name = "tet" + std::to_string(resolution) + ".cvox";
        if (resolution == 128) put(dir, "fuzz_cvox", name, out.str());
        put(dir, "fuzz_cvox_blocks", name, out.str());
    }
    // A partial voxelization of the tetrahedron: its chunks at 16^3 (one block), and at 128^3.
    for (const int resolution : {16, 128}) {
        voxel::VoxelizeOptions o;
        o.resolution = resolution;
        const auto mesh = tetrahedron();
        std::ostringstream out;
        voxel::writePartialVoxelization(voxel::voxelizeChunks(*mesh, o, 0, mesh->chunkCount()), out);
        put(dir, "fuzz_partial_voxelization", "tet" + std::to_string(resolution) + ".cvxp", out.str());
    }
    // The tetrahedron's one range at 128^3 (two levels), split at level 0 (with the copies the
    // join builds level 1 from) and at level 1 (the range builds both).
    for (const uint32_t split : {0u, 1u}) {
        voxel::VoxelizeOptions o;
        o.resolution = 128;
        const auto mesh = tetrahedron();
        std::vector<voxel::PartialVoxelization> parts;
        parts.push_back(voxel::voxelizeChunks(*mesh, o, 0, mesh->chunkCount()));
        std::ostringstream out;
        lod::buildPyramidRange(voxel::mergePartialVoxelizations(std::move(parts)), {}, split, out);
        put(dir, "fuzz_pyramid_range", "tet128-split" + std::to_string(split) + ".cvxr", out.str());
    }
    fs::remove(fs::temp_directory_path() / "cuberille-seed-tet.obj");
    return 0;
}
