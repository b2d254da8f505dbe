#include "render/frame_settings.h"

#include <charconv>
#include <cmath>
#include <vector>

#include "raster/sample_pattern.h"
#include "raster/srgb.h"
#include "scene/input_error.h"

namespace cuberille::render {

void validateFrameOptions(int width, int height, int msaa, int threads) {
    using scene::InputError;
    if (width < 1 || height < 1 || width > raster::kMaxFramebufferPixels || height > raster::kMaxFramebufferPixels)
        throw InputError("--width/--height: " + std::to_string(width) + "x" + std::to_string(height) +
                         " is outside 1.." + std::to_string(raster::kMaxFramebufferPixels));
    if (!raster::isSupportedSampleCount(msaa))
        throw InputError("--msaa: " + std::to_string(msaa) + " is not 1, 2, 4, 8 or 16");
    if (threads < 0) throw InputError("--threads: must be 0 (all cores) or more");
}

raster::FramebufferDesc framebufferDesc(const FrameSettings& o) {
    raster::FramebufferDesc d;
    d.widthPixels = o.width;
    d.heightPixels = o.height;
    d.samples = o.msaa;
    d.depthConvention = o.depth;
    d.recordOverdraw = o.view == View::Overdraw;
    d.recordBlockClasses = o.view == View::Tiles;
    return d;
}

glm::vec4 clearColorFor(const glm::vec4& display) {
    const float a = display.a;
    return {float(raster::decodeSrgb(display.r)) * a, float(raster::decodeSrgb(display.g)) * a,
            float(raster::decodeSrgb(display.b)) * a, a};
}

glm::vec4 parseBackground(const std::string& text) {
    const std::string problem = "--background " + text + ": expected R,G,B or R,G,B,A, each in [0, 1]";
    std::vector<std::string> parts;
    for (size_t start = 0;;) {
        const size_t end = std::min(text.find(',', start), text.size());
        parts.push_back(text.substr(start, end - start));
        if (end == text.size()) break;
        start = end + 1;
    }
    if (parts.size() != 3 && parts.size() != 4) throw scene::InputError(problem);
    glm::vec4 v(0.0f, 0.0f, 0.0f, 1.0f);
    for (size_t k = 0; k < parts.size(); ++k) {
        const char* first = parts[k].data();
        const auto [last, ec] = std::from_chars(first, first + parts[k].size(), v[int(k)]);
        if (ec != std::errc() || last != first + parts[k].size() || !(v[int(k)] >= 0.0f && v[int(k)] <= 1.0f))
            throw scene::InputError(problem);
    }
    return v;
}

glm::vec3 parseVector3(const std::string& text, const std::string& option) {
    glm::vec3 v(0.0f);
    size_t start = 0;
    for (int k = 0; k < 3; ++k) {
        const size_t end = k < 2 ? text.find(',', start) : text.size();
        if (end == std::string::npos) break;
        const std::string part = text.substr(start, end - start);
        const char* first = part.data();
        const auto [last, ec] = std::from_chars(first, first + part.size(), v[k]);
        if (ec != std::errc() || last != first + part.size() || !std::isfinite(v[k]))
            throw scene::InputError(option + " " + text + ": expected three numbers X,Y,Z");
        if (k == 2) return v;
        start = end + 1;
    }
    throw scene::InputError(option + " " + text + ": expected three numbers X,Y,Z");
}

View parseView(const std::string& name) {
    if (name == "color") return View::Color;
    if (name == "depth") return View::Depth;
    if (name == "tiles") return View::Tiles;
    if (name == "overdraw") return View::Overdraw;
    if (name == "lod") return View::Lod;
    if (name == "visibility") return View::Visibility;
    if (name == "shadow-pixels") return View::ShadowPixels;
    if (name == "normals") return View::Normals;
    throw scene::InputError("--view: '" + name + "' is not color, depth, normals, tiles, overdraw, lod, visibility or shadow-pixels");
}

TextureFilterOverride parseTextureFilter(const std::string& name) {
    if (name == "file") return TextureFilterOverride::File;
    if (name == "nearest") return TextureFilterOverride::Nearest;
    if (name == "bilinear") return TextureFilterOverride::Bilinear;
    if (name == "trilinear") return TextureFilterOverride::Trilinear;
    throw scene::InputError("--texture-filter: '" + name + "' is not file, nearest, bilinear or trilinear");
}

raster::DepthConvention parseDepthConvention(const std::string& name) {
    if (name == "standard") return raster::DepthConvention::Standard;
    if (name == "reversed") return raster::DepthConvention::Reversed;
    throw scene::InputError("--depth: '" + name + "' is not standard or reversed");
}

rt::BvhUpdateMethod parseBvhUpdate(const std::string& name) {
    if (name == "refit") return rt::BvhUpdateMethod::Refit;
    if (name == "lazy") return rt::BvhUpdateMethod::Lazy;
    if (name == "rebuild") return rt::BvhUpdateMethod::Rebuild;
    throw scene::InputError("--bvh-update: '" + name + "' is not refit, lazy or rebuild");
}

rt::CasterAccel parseAccel(const std::string& name) {
    if (name == "bvh") return rt::CasterAccel::Bvh;
    if (name == "grid") return rt::CasterAccel::Grid;
    throw scene::InputError("--accel: '" + name + "' is not bvh or grid");
}

void applyAccel(const std::string& name, FrameSettings& f) {
    rt::VoxelStructure voxel;
    if (name == "bvh" || name == "grid") {
        f.accel = parseAccel(name);
        f.voxelAccel = rt::VoxelStructure::Bvh;
    } else if (rt::parseVoxelStructure(name, &voxel)) {
        f.accel = rt::CasterAccel::Bvh;
        f.voxelAccel = voxel;
    } else {
        throw scene::InputError("--accel: '" + name + "' is not bvh, grid, kdtree, octree or bvh8");
    }
}

const char* accelName(rt::CasterAccel accel) { return accel == rt::CasterAccel::Grid ? "grid" : "bvh"; }

Renderer parseRenderer(const std::string& name) {
    if (name == "raster") return Renderer::Raster;
    if (name == "raytrace") return Renderer::Raytrace;
    throw scene::InputError("--renderer: '" + name + "' is not raster or raytrace");
}

const char* rendererName(Renderer renderer) { return renderer == Renderer::Raytrace ? "raytrace" : "raster"; }

FrameVisibility parseFrameVisibility(const std::string& name) {
    if (name == "auto") return FrameVisibility::Auto;
    if (name == "shadow-stage") return FrameVisibility::ShadowStage;
    if (name == "depth-test") return FrameVisibility::DepthTest;
    throw scene::InputError("--frame-visibility: '" + name + "' is not auto, shadow-stage or depth-test");
}

const char* frameVisibilityName(FrameVisibility v) {
    return v == FrameVisibility::Auto ? "auto" : v == FrameVisibility::ShadowStage ? "shadow-stage" : "depth-test";
}

const char* textureFilterName(TextureFilterOverride f) {
    switch (f) {
        case TextureFilterOverride::File: return "file";
        case TextureFilterOverride::Nearest: return "nearest";
        case TextureFilterOverride::Bilinear: return "bilinear";
        case TextureFilterOverride::Trilinear: return "trilinear";
    }
    return "?";
}

const char* viewName(View v) {
    switch (v) {
        case View::Color: return "color";
        case View::Depth: return "depth";
        case View::Tiles: return "tiles";
        case View::Overdraw: return "overdraw";
        case View::Lod: return "lod";
        case View::Visibility: return "visibility";
        case View::ShadowPixels: return "shadow-pixels";
        case View::Normals: return "normals";
    }
    return "?";
}

}  // namespace cuberille::render
