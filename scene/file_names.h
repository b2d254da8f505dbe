#pragma once
// File kinds as the tool recognises them by name: one classifier for every command, comparing
// case-insensitively, so `DRAGON.PLY.GZ` is a gzip-compressed PLY like `dragon.ply.gz` and
// `MODEL.GLB` a binary glTF like `model.glb`.

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <string>
#include <string_view>

namespace cuberille::scene {

enum class FileKind {
    TriangleList,    // .tri (DESIGN.md)
    Ply,             // .ply, .ply.gz
    Obj,             // .obj
    Gltf,            // .gltf
    Glb,             // .glb
    VoxelModel,      // .cvox
    GeometryStream,  // .cgs
    Png,             // .png
    Exr,             // .exr
    Jpeg,            // .jpg, .jpeg
    Unknown,
};

inline std::string lowercase(std::string s) {
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return s;
}

/// Whether the file name ends with suffix (lower case, e.g. ".ply.gz"), ignoring case.
inline bool fileNameEndsWith(const std::filesystem::path& path, std::string_view suffix) {
    const std::string n = lowercase(path.filename().string());
    return n.size() >= suffix.size() && n.compare(n.size() - suffix.size(), suffix.size(), suffix) == 0;
}

/// The path's last extension in lower case (".exr"), empty when it has none.
inline std::string lowerExtension(const std::filesystem::path& path) { return lowercase(path.extension().string()); }

inline FileKind fileKindOf(const std::filesystem::path& path) {
    static constexpr std::pair<std::string_view, FileKind> kSuffixes[] = {
        {".tri", FileKind::TriangleList}, {".ply", FileKind::Ply},    {".ply.gz", FileKind::Ply},
        {".obj", FileKind::Obj},          {".gltf", FileKind::Gltf},  {".glb", FileKind::Glb},
        {".cvox", FileKind::VoxelModel},  {".cgs", FileKind::GeometryStream},
        {".png", FileKind::Png},          {".exr", FileKind::Exr},    {".jpg", FileKind::Jpeg},
        {".jpeg", FileKind::Jpeg}};
    for (const auto& [suffix, kind] : kSuffixes)
        if (fileNameEndsWith(path, suffix)) return kind;
    return FileKind::Unknown;
}

inline bool isGltfKind(FileKind k) { return k == FileKind::Gltf || k == FileKind::Glb; }
/// A mesh a model loader reads: PLY, OBJ or glTF.
inline bool isMeshKind(FileKind k) { return k == FileKind::Ply || k == FileKind::Obj || isGltfKind(k); }

}  // namespace cuberille::scene
