#pragma once
// Wavefront OBJ meshes with MTL colours. Reads `v x y z [r g b]`, `vn`, `f` with any of the
// forms i, i/t, i/t/n, i//n (negative indices count back from the end), polygons as fans,
// `usemtl` (one Mesh per material, in order of first use) and `mtllib` (the `Kd` diffuse colour,
// sRGB-encoded, converted to linear). A face that mixes vertices with and without normals gets
// computed normals. Unsupported statements (vt, o, g, s, l, p) are skipped.
//
// Bad input throws InputError naming the file, the line and the problem; a missing or broken
// MTL file warns (through `warn`) and falls back to the default colour.

#include <filesystem>
#include <string>
#include <vector>

#include "scene/input_error.h"
#include "scene/mesh.h"

namespace cuberille::scene {

std::vector<Mesh> parseObj(const std::string& text, const std::string& fileName,
                           const std::filesystem::path& directory, const WarningSink& warn);
std::vector<Mesh> loadObj(const std::filesystem::path& path, const WarningSink& warn);

}  // namespace cuberille::scene
