#pragma once
// A scene read once and rendered as often as asked (render/renderer.h): a .tri file, a built-in
// scene, a mesh file (PLY, OBJ, glTF) or a voxel model (.cvox). What does not depend on the
// frame is kept between renders:
//   - the file itself: a glTF is parsed once and posed again only when a frame asks for another
//     animation time (each texture decoded once); PLY and OBJ meshes are read once;
//   - the hierarchies over its triangles (the frustum cull's, the shadow casters'), built on the
//     first frame that needs them and refitted when a later frame poses the animation elsewhere
//     (render/scene_culling.h, render/scene_shadows.h);
//   - a voxel model's blocks.
// The image of a frame never depends on what was rendered before it: only the work differs (a
// refit instead of a build), and --stats says which. Occlusion culling of voxel models starts
// from nothing each render, so its counts do not depend on the order of calls either.
//
// Frames are drawn one at a time in a process, of one LoadedScene or several (a second thread's
// render waits): each frame already runs on every core it may, and its thread limit is the
// process's (render/renderer.cpp).

#include <memory>
#include <string>
#include <vector>

#include "render/frame_settings.h"
#include "scene/file_names.h"
#include "scene/input_error.h"

namespace cuberille::render {

class LoadedScene {
public:
    /// `scene`: a .tri, .ply, .ply.gz, .obj, .gltf, .glb or .cvox path, or a built-in scene's
    /// name. Warnings about what the file holds go to `warn` (none by default; the library
    /// prints nothing). Throws scene::InputError for a name that is no scene and for unreadable
    /// or malformed files, with the messages the command line prints.
    explicit LoadedScene(const std::string& scene, const SceneOptions& options = {}, scene::WarningSink warn = {});
    LoadedScene(LoadedScene&&) noexcept;
    LoadedScene& operator=(LoadedScene&&) noexcept;
    ~LoadedScene();

    /// The path or built-in name it was loaded from.
    const std::string& name() const;
    bool isTriangleList() const;  // a 2D .tri scene (window-space triangles, no camera)
    bool isVoxelModel() const;    // a .cvox model, drawn through level-of-detail selection
    bool is3d() const { return !isTriangleList() && !isVoxelModel(); }
    bool isGltf() const;
    const SceneOptions& options() const;
    /// The file's read and parse, in milliseconds (a glTF's first pose is part of its first frame).
    double loadMs() const;
    /// glTF: the animations by name in file order ("" for an unnamed one); empty for others.
    std::vector<std::string> animations() const;

    struct State;  // render/renderer.cpp draws from it

private:
    friend struct SceneAccess;
    std::unique_ptr<State> state_;
};

}  // namespace cuberille::render
