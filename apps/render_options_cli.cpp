#include "apps/render_options_cli.h"

#include "scene/input_error.h"
#include "scene/procedural.h"

namespace cuberille::apps {

/// The frame's size, samples and the worker threads, as every rendering command takes them.
void addFrameOptions(CLI::App* command, int& width, int& height, int& msaa, int& threads) {
    command->add_option("--width", width, "Image width in pixels")->capture_default_str();
    command->add_option("--height", height, "Image height in pixels")->capture_default_str();
    command->add_option("--msaa", msaa, "Samples per pixel: 1, 2, 4, 8 or 16")->capture_default_str();
    command->add_option("--threads", threads, "Worker threads (0 = all cores)")->capture_default_str();
}


CLI::App* addRenderCommand(CLI::App& app, RenderOptions& o, RenderNames& names) {
    CLI::App* render = app.add_subcommand(
        "render", "Render one frame of a scene to an image (PNG: sRGB 8-bit; EXR: linear float)");
    std::string scenes;
    for (const auto& n : scene::proceduralSceneNames()) scenes += " " + n;
    render->add_option("scene", o.scene,
                       "A .tri, .ply, .ply.gz, .obj, .gltf, .glb or .cvox file, or a built-in scene:" + scenes)
        ->required();
    addFrameOptions(render, o.width, o.height, o.msaa, o.threads);
    render->add_option("--out", o.out, "Output image: .png (sRGB, 8 or 16 bits, alpha with a transparent --background), .exr (linear float RGBA) or .jpg")->required();
    render->add_option("--background", names.background,
                       "R,G,B[,A]: the background as display (sRGB) values and opacity in [0, 1], instead of the scene's; "
                       "an opacity below 1 writes alpha (PNG with straight alpha, EXR premultiplied)");
    render->add_option("--png-bits", o.pngBits, "Bits per PNG channel: 8 or 16")->capture_default_str();
    render->add_option("--stats", o.statsPath, "Write per-stage counters and timings as JSON");
    render->add_option("--view", names.view, "What to show: color, depth, normals (world-space vertex normals as "
                                       "colours, x red, y green, z blue), tiles (coarse block "
                                       "classes), overdraw (depth-passing samples), lod (voxel models: "
                                       "blocks coloured by level) or visibility (voxel models: drawn green, "
                                       "source triangles yellow, occlusion-culled red) or shadow-pixels "
                                       "(the pixels the shadow stage traced rays for, red)")
        ->capture_default_str();
    render->add_flag("--legend,!--no-legend", o.legend,
                     "The tiles, overdraw, lod and visibility views: a legend of their colours in the lower-left corner");
    render->add_option("--detail", o.detail, "Tessellation scale of built-in scenes")
        ->capture_default_str();
    render->add_option("--azimuth", o.azimuth, "Camera azimuth for mesh files, degrees about +y")
        ->capture_default_str();
    render->add_option("--elevation", o.elevation, "Camera elevation for mesh files, degrees")
        ->capture_default_str();
    render->add_option("--camera-index", o.cameraIndex,
                       "Use the file's N-th camera (glTF, in node order) instead of framing the model");
    render->add_option("--eye", names.eye, "Place the camera at X,Y,Z (world units) instead of framing the model");
    render->add_option("--target", names.target, "With --eye: the point X,Y,Z looked at (default: the model's centre)");
    render->add_option("--up", names.up, "With --eye: the up direction X,Y,Z (default: 0,1,0)");
    render->add_option("--fov", names.fovDegrees, "With --eye: vertical field of view, degrees (default: the framing one's)");
    render->add_option("--up-axis", names.upAxis, "Mesh files: the file's up axis, y or z (z-up scans are turned to y-up)")
        ->capture_default_str();
    render->add_option("--zoom", o.zoom,
                       "Magnify the view F times, whichever camera frames it (the field of view narrows; the eye stays)")
        ->capture_default_str();
    render->add_flag("--ground", o.ground,
                     "Model files: stand the model on a grey floor (3 times its half-width around it) that catches its "
                     "shadows; the framing stays the model's");
    render->add_flag("--shadow-catcher", o.shadowCatcher,
                     "With --ground and --shadows: the floor shows the background where it is lit and only darkens "
                     "it where the model's shadow falls (directional lights only)");
    render->add_flag("--orthographic", o.orthographic,
                     "A parallel projection: the target's plane at the size the perspective camera shows it "
                     "(--zoom narrows it)");
    render->add_option("--animation", o.animation,
                       "glTF: the animation --time, --animate and --turntable pose, by name or index (default: the first)");
    render->add_option("--time", o.timeSeconds,
                       "glTF: pose the animation (--animation; the first by default) at this time, in seconds")
        ->capture_default_str();
    render->add_option("--turntable", o.turntable,
                       "Write N frames turning around the scene (OUT_000.png, OUT_001.png, ...)")
        ->check(CLI::Range(1, 3600));
    render->add_option("--animate", o.animate,
                       "glTF: write N frames of the animation (--animation) from --time, --fps apart (OUT_000.png, ...)")
        ->check(CLI::Range(1, 3600));
    render->add_option("--fps", o.fps, "With --animate: frames a second of animation time")->capture_default_str();
    render->add_option("--supersample", o.supersample,
                       "Render N x N times the pixels and box-filter down: N² samples per pixel on a grid (1..16)")
        ->capture_default_str();
    render->add_option("--texture-filter", names.textureFilter,
                       "Texture filtering: file (each texture's own sampler), or nearest, bilinear or trilinear for "
                       "every texture")
        ->capture_default_str();
    render->add_option("--depth", names.depth,
                       "Depth convention: standard (0 near, 1 far) or reversed (1 near, 0 far: float precision "
                       "where distant surfaces need it)")
        ->capture_default_str();
    render->add_flag("--frustum-cull", o.frustumCull,
                     "3D scenes: cull triangles against the view frustum through a BVH (refitted per --animate frame)");
    render->add_option("--bvh-update", names.bvhUpdate,
                       "With --animate: how the frustum cull's, the shadow stage's and the camera rays' BVHs follow each pose: refit "
                       "(bottom-up, rebuilt past Lauterbach's 0.4), lazy (Larsson's: the upper half refitted, the "
                       "rest on first touch by a ray) or rebuild (a new tree every frame)")
        ->capture_default_str();
    render->add_option("--renderer", names.renderer,
                       "What finds the surface each sample sees: raster (the rasterizer's depth test) or raytrace "
                       "(3D scenes and voxel models: a camera ray per sample through --accel's structure; the same "
                       "shading, shadows and occlusion)")
        ->capture_default_str();
    render->add_option("--frame-visibility", names.frameVisibility,
                       "A shadowed raster frame of one sample: auto (shade the shadow stage's visibility buffer instead "
                       "of drawing the scene again where the scene is dense enough to pay), shadow-stage (wherever it "
                       "serves) or depth-test (always draw again); the same image every way")
        ->capture_default_str();
    render->add_option("--accel", names.accel,
                       "What answers the rays (--renderer raytrace's camera rays, and the shadow stage's for --shadows "
                       "hybrid/raytraced/auto and --ao): bvh (built once, kept for every view and following each "
                       "--animate pose as --bvh-update says) or grid (a uniform grid rebuilt from scratch for every "
                       "frame, Wald et al. 2006); for a voxel model's camera rays, bvh, kdtree or octree over its "
                       "voxels (Chajdas 2015, chapter 5), or bvh8 (that BVH with eight children a node, tested in "
                       "vector lanes). The same images whichever")
        ->capture_default_str();
    render->add_option("--pixel-error", o.pixelError,
                       "Voxel models: refine blocks until a voxel's edge projects to at most this many pixels "
                       "(0: always the finest level)")
        ->capture_default_str();
    render->add_option("--voxel-resolution", o.voxelResolution,
                       "Voxel models: refine no finer than this resolution, one of the model's levels (0: the finest)")
        ->capture_default_str();
    render->add_flag("--no-hybrid", o.noHybrid,
                     "Voxel models: never draw source triangles where even the finest voxels are too coarse");
    render->add_flag("--no-occlusion", o.noOcclusion, "Voxel models: no occlusion culling (of blocks hidden last frame, or of voxels behind what the frame drew)");
    render->add_flag("--debug-camera", o.debugCamera,
                     "Voxel models: draw what the camera's frame selected as seen from its side, farther and above");
    render->add_option("--warmup", o.warmup,
                       "Voxel models: frames rendered first so occlusion culling has the frame before to learn from")
        ->capture_default_str();
    render->add_option("--shadows", names.shadows,
                       "Shadows from the scene's lights: none, map (shadow maps), hybrid (maps, with shadow rays "
                       "for the pixels a map may get wrong), raytraced (a shadow ray per pixel, the reference) or auto "
                       "(per light and frame, hybrid or raytraced, whichever a cost model predicts cheaper)")
        ->capture_default_str();
    render->add_flag("--soft", o.shadows.soft, "Area lights: soft shadows (N x N rays where rays are traced)");
    render->add_option("--light-radius", o.shadows.lightRadius,
                       "With --soft: light radius in world units (point, spot); tangent of the angular radius "
                       "(directional)")
        ->capture_default_str();
    render->add_option("--shadow-map-size", o.shadows.mapSizeTexels, "Shadow map side in texels (per cube face)")
        ->capture_default_str();
    render->add_option("--soft-samples", o.shadows.softSamplesPerSide, "With --soft: N, for N x N rays per pixel")
        ->capture_default_str();
    render->add_option("--shadow-focus", names.shadowFocus,
                       "What a sun's shadow map covers: view (the casters over what the frame sees: finer texels, "
                       "drawn again when the camera moves), scene (every caster: drawn once for a turntable or a "
                       "batch of views) or auto (scene for --turntable, else view)")
        ->capture_default_str();
    render->add_option("--ao", o.ambientOcclusion.raysPerPixel,
                       "Ambient occlusion: N rays a pixel from the surface it sees (cosine-weighted), darkening the "
                       "ambient and environment light where geometry within --ao-distance hides the sky; 0: none")
        ->capture_default_str();
    render->add_option("--ao-distance", o.ambientOcclusion.maxDistance,
                       "With --ao: how far the rays look, in world units (0: a tenth of the model's bounding-box "
                       "diagonal)")
        ->capture_default_str();
    render->add_option("--environment", o.environment,
                       "Image-based lighting: neutral (the built-in studio) or an equirectangular radiance map (.hdr, "
                       ".exr); it replaces the ambient term and, for a model without lights of its own, the default "
                       "key light");
    render->add_option("--environment-intensity", o.environmentIntensity, "With --environment: its radiance scaled")
        ->capture_default_str();
    render->add_flag("--quiet", o.quiet, "Print nothing on success");
    return render;
}

void applyRenderNames(const RenderNames& names, RenderOptions& o) {
    o.view = parseView(names.view);
    o.shadows.mode = render::parseShadowMode(names.shadows);
    if (names.shadowFocus != "auto") o.shadowFocus = render::parseMapFocus(names.shadowFocus);
    o.textureFilter = parseTextureFilter(names.textureFilter);
    o.depth = parseDepthConvention(names.depth);
    o.bvhUpdate = parseBvhUpdate(names.bvhUpdate);
    render::applyAccel(names.accel, o);
    o.renderer = render::parseRenderer(names.renderer);
    o.frameVisibility = render::parseFrameVisibility(names.frameVisibility);
    if (names.upAxis != "y" && names.upAxis != "z")
        throw scene::InputError("--up-axis " + names.upAxis + ": expected y or z");
    o.zUp = names.upAxis == "z";
    if (!names.background.empty()) o.background = parseBackground(names.background);
    const bool placed = !names.eye.empty();
    if (!placed && (!names.target.empty() || !names.up.empty() || names.fovDegrees != 0.0f))
        throw scene::InputError("--target, --up and --fov: only with --eye");
    if (placed) {
        scene::CameraPlacement p;
        p.eye = parseVector3(names.eye, "--eye");
        if (!names.target.empty()) p.target = parseVector3(names.target, "--target");
        if (!names.up.empty()) p.up = parseVector3(names.up, "--up");
        p.verticalFovDegrees = names.fovDegrees;
        o.placement = p;
    }
}

void parseSubcommandArguments(const std::string& name, const std::vector<std::string>& arguments,
                              const std::function<void(CLI::App&)>& addCommand) {
    CLI::App app;
    addCommand(app);
    std::vector<std::string> reversed{arguments.rbegin(), arguments.rend()};  // CLI11 takes them last first
    reversed.push_back(name);
    try {
        app.parse(reversed);
    } catch (const CLI::ParseError& e) {
        throw scene::InputError(e.what());
    }
}

RenderOptions parseRenderArguments(const std::vector<std::string>& arguments) {
    RenderOptions o;
    RenderNames names;
    parseSubcommandArguments("render", arguments, [&](CLI::App& app) { addRenderCommand(app, o, names); });
    applyRenderNames(names, o);
    return o;
}

}  // namespace cuberille::apps
