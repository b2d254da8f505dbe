#include "scene/gltf_loader.h"

#include <charconv>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <deque>
#include <map>
#include <set>
#include <string_view>
#include <string>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <tiny_gltf.h>
#include <webp/decode.h>

#include "scene/gltf_compression.h"
#include "scene/input_error.h"
#include "scene/ply_loader.h"  // readFileBytes
#include "scene/file_names.h"

namespace cuberille::scene {
namespace {

constexpr int kMaxNodeDepth = 256;

using TextureCache = std::map<std::pair<int, bool>, std::shared_ptr<const raster::Texture>>;  // (index, sRGB)

// One pose of a parsed document. The texture cache and the warnings already given belong to the
// document, so a second pose decodes no texture and repeats no warning.
class GltfReader {
public:
    GltfReader(const tinygltf::Model& model, const std::string& file, const WarningSink& warn, float timeSeconds,
               const std::string& animation, TextureCache& textures, std::set<std::string>& warned)
        : model_(model), file_(file), warn_(warn), warned_(warned), textures_(textures), timeSeconds_(timeSeconds),
          animation_(chooseAnimation(animation)) {}

    GltfScene read() {
        refuseRequiredExtensions();
        warnAboutUnsupported();
        poseAnimation();
        if (!model_.scenes.empty()) {
            const int sceneIndex = model_.defaultScene >= 0 ? model_.defaultScene : 0;
            if (sceneIndex >= int(model_.scenes.size())) fail("scene " + std::to_string(sceneIndex), "does not exist");
            globals_.assign(model_.nodes.size(), glm::mat4(1.0f));
            inScene_.assign(model_.nodes.size(), false);
            parents_.assign(model_.nodes.size(), -1);
            for (size_t p = 0; p < model_.nodes.size(); ++p)
                for (int c : model_.nodes[p].children)
                    if (c >= 0 && c < int(parents_.size()) && parents_[c] < 0) parents_[c] = int(p);
            for (int node : model_.scenes[sceneIndex].nodes) visit(node, glm::mat4(1.0f), 0);
            // Meshes after every global transform is known: a skin's joints may come later.
            for (int node : visited_) {
                const tinygltf::Node& n = model_.nodes[node];
                if (n.mesh >= 0) addMesh(n.mesh, globals_[node], n.skin, node);
                if (n.camera >= 0) addCamera(n.camera, globals_[node], "node " + std::to_string(node));
                addLight(n, globals_[node], "node " + std::to_string(node));
            }
        } else {
            // No scene: every mesh once, untransformed (glTF 2.0 §3.3 allows files without scenes).
            for (size_t m = 0; m < model_.meshes.size(); ++m) addMesh(int(m), glm::mat4(1.0f), -1, -1);
        }
        stats_.texturesDecoded = 0;
        for (const auto& key : texturesUsed_) stats_.texturesDecoded += textures_.at(key) != nullptr;
        return {std::move(meshes_), std::move(cameras_), std::move(lights_), stats_};
    }

private:
    [[noreturn]] void fail(const std::string& where, const std::string& problem) const {
        throw InputError(file_ + ": " + where + ": " + problem);
    }

    void warnOnce(const std::string& message) {
        if (warned_.insert(message).second) warn_(file_ + ": " + message);
    }

    // The extensions this reader honours. KHR_mesh_quantization needs nothing of its own: every
    // attribute is read through AccessorView, which takes any component type, normalised or not.
    // Compressed views and primitives are decoded before the reader runs (scene/gltf_compression.h).
    static constexpr std::array<std::string_view, 15> kSupportedExtensions = {
        "KHR_lights_punctual", "KHR_materials_unlit", "KHR_texture_transform", "KHR_mesh_quantization", "EXT_meshopt_compression",
        "KHR_draco_mesh_compression",
        "KHR_materials_emissive_strength", "KHR_materials_ior", "KHR_materials_pbrSpecularGlossiness", "KHR_materials_specular",
        "KHR_materials_clearcoat", "KHR_materials_sheen", "KHR_materials_transmission", "KHR_materials_volume", "EXT_texture_webp"};
    static bool supportedExtension(const std::string& name) {
        return std::find(kSupportedExtensions.begin(), kSupportedExtensions.end(), name) != kSupportedExtensions.end();
    }
    // "A, B and C", in the order above: what refusals say the reader reads.
    static std::string supportedExtensionList() {
        std::string list;
        for (size_t i = 0; i < kSupportedExtensions.size(); ++i)
            list += (i == 0 ? "" : i + 1 == kSupportedExtensions.size() ? " and " : ", ") + std::string(kSupportedExtensions[i]);
        return list;
    }

    // A file that requires an extension Cuberille cannot honour cannot be drawn as its author
    // meant (glTF 2.0 §3.12): refused, naming every such extension, where one that is merely used
    // falls back to the core data with a warning.
    void refuseRequiredExtensions() const {
        std::string missing;
        for (const std::string& ext : model_.extensionsRequired)
            if (!supportedExtension(ext)) missing += (missing.empty() ? "" : ", ") + ext;
        if (!missing.empty())
            throw InputError(file_ + ": requires " + missing + ", which Cuberille cannot read yet (it reads " +
                             supportedExtensionList() + ")");
    }

    void warnAboutUnsupported() {
        if (model_.animations.size() > 1 && animation_ == 0 && !animationChosen_)
            warnOnce("plays the first of " + std::to_string(model_.animations.size()) + " animations (" + animationNames() +
                     "); --animation NAME|INDEX chooses another");
        for (const auto& ext : model_.extensionsUsed)
            if (!supportedExtension(ext)) warnOnce("extension " + ext + " is not supported yet and was ignored");
    }

    struct NodePose {
        glm::vec3 translation{0.0f};
        glm::quat rotation{1.0f, 0.0f, 0.0f, 0.0f};
        glm::vec3 scale{1.0f};
    };

    glm::mat4 localTransform(int index, const tinygltf::Node& n) const {
        if (const auto it = pose_.find(index); it != pose_.end()) {
            const NodePose& p = it->second;  // animated nodes use TRS (glTF 2.0 §3.11)
            return glm::translate(glm::mat4(1.0f), p.translation) * glm::mat4_cast(p.rotation) *
                   glm::scale(glm::mat4(1.0f), p.scale);
        }
        if (n.matrix.size() == 16) {
            glm::dmat4 m;
            for (int i = 0; i < 16; ++i) glm::value_ptr(m)[i] = n.matrix[i];  // column-major
            return glm::mat4(m);
        }
        glm::dmat4 m(1.0);
        if (n.translation.size() == 3) m = glm::translate(m, glm::dvec3(n.translation[0], n.translation[1], n.translation[2]));
        if (n.rotation.size() == 4)
            m *= glm::mat4_cast(glm::normalize(glm::dquat(n.rotation[3], n.rotation[0], n.rotation[1], n.rotation[2])));
        if (n.scale.size() == 3) m = glm::scale(m, glm::dvec3(n.scale[0], n.scale[1], n.scale[2]));
        return glm::mat4(m);
    }

    void visit(int index, const glm::mat4& parent, int depth) {
        const std::string where = "node " + std::to_string(index);
        if (index < 0 || index >= int(model_.nodes.size())) fail(where, "does not exist");
        if (depth > kMaxNodeDepth) fail(where, "the hierarchy is deeper than " + std::to_string(kMaxNodeDepth) + " (a cycle?)");
        const tinygltf::Node& n = model_.nodes[index];
        const glm::mat4 world = parent * localTransform(index, n);
        globals_[index] = world;
        inScene_[index] = true;
        visited_.push_back(index);
        for (int child : n.children) visit(child, world, depth + 1);
    }

    // A node's world transform; joints need not be in the scene (glTF 2.0 §3.7.3), and then
    // it comes from their own ancestry.
    glm::mat4 globalOf(int node, const std::string& where) const {
        if (node < int(inScene_.size()) && inScene_[node]) return globals_[node];
        glm::mat4 world = localTransform(node, model_.nodes[node]);
        int child = node;
        for (int depth = 0;; ++depth) {
            const int parent = parents_[child];
            if (parent < 0) return world;
            if (depth > kMaxNodeDepth) fail(where, "joint " + std::to_string(node) + "'s ancestry is deeper than " + std::to_string(kMaxNodeDepth));
            if (parent < int(inScene_.size()) && inScene_[parent]) return globals_[parent] * world;
            world = localTransform(parent, model_.nodes[parent]) * world;
            child = parent;
        }
    }

    // KHR_lights_punctual: a light sits at its node's origin and shines down its -z. glTF gives
    // lux (directional) or candela (point, spot) for a BRDF with diffuse albedo / pi; ours
    // folds the pi into the light (raster::Light), hence the division.
    void addLight(const tinygltf::Node& n, const glm::mat4& world, const std::string& where) {
        const auto ext = n.extensions.find("KHR_lights_punctual");
        if (ext == n.extensions.end() || !ext->second.Has("light")) return;
        const int index = ext->second.Get("light").GetNumberAsInt();
        if (index < 0 || index >= int(model_.lights.size())) fail(where, "light " + std::to_string(index) + " does not exist");
        const tinygltf::Light& l = model_.lights[index];
        raster::Light light;
        if (l.type == "directional") {
            light.type = raster::LightType::Directional;
        } else if (l.type == "point") {
            light.type = raster::LightType::Point;
        } else if (l.type == "spot") {
            light.type = raster::LightType::Spot;
            light.cosInnerCone = float(std::cos(l.spot.innerConeAngle));
            light.cosOuterCone = float(std::cos(l.spot.outerConeAngle));
        } else {
            warnOnce("light " + std::to_string(index) + " has unknown type \"" + l.type + "\"; ignored");
            return;
        }
        light.position = glm::vec3(world[3]);
        const glm::vec3 axis(world[2]);
        light.direction = glm::length(axis) > 0.0f ? -glm::normalize(axis) : glm::vec3(0.0f, 0.0f, -1.0f);
        const glm::vec3 color = l.color.size() >= 3 ? glm::vec3(l.color[0], l.color[1], l.color[2]) : glm::vec3(1.0f);
        light.intensity = color * float(l.intensity / M_PI);
        light.range = float(std::max(0.0, l.range));
        lights_.push_back(light);
    }

    // A camera looks down its node's -z with +y up (glTF 2.0 §3.10).
    void addCamera(int index, const glm::mat4& world, const std::string& where) {
        if (index >= int(model_.cameras.size())) fail(where, "camera " + std::to_string(index) + " does not exist");
        const tinygltf::Camera& c = model_.cameras[index];
        Camera cam;
        cam.position = glm::vec3(world[3]);
        cam.target = cam.position - glm::normalize(glm::vec3(world[2]));
        cam.up = glm::normalize(glm::vec3(world[1]));
        if (c.type == "orthographic") {
            cam.orthographic = true;
            cam.orthographicHalfHeight = float(c.orthographic.ymag);
            cam.nearPlane = float(c.orthographic.znear);
            cam.farPlane = float(c.orthographic.zfar);
        } else {
            cam.verticalFovDegrees = float(glm::degrees(c.perspective.yfov));
            cam.nearPlane = float(c.perspective.znear);
            // An infinite projection (no zfar) gets a far plane a million near planes away.
            cam.farPlane = c.perspective.zfar > 0.0 ? float(c.perspective.zfar) : cam.nearPlane * 1e6f;
        }
        if (!(cam.nearPlane > 0.0f) || !(cam.farPlane > cam.nearPlane))
            fail(where, "camera " + std::to_string(index) + " has invalid near/far planes");
        cameras_.push_back(cam);
    }

    // The accessor's element i, component c, as float (normalised integers scaled to [0, 1]).
    struct AccessorView {
        const unsigned char* data;
        size_t stride, count;
        int componentType, components;
        bool normalized;

        float get(size_t i, int c) const {
            const unsigned char* p = data + i * stride;
            switch (componentType) {
                case TINYGLTF_COMPONENT_TYPE_FLOAT: { float v; std::memcpy(&v, p + 4 * c, 4); return v; }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: { const float v = p[c]; return normalized ? v / 255.0f : v; }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t v; std::memcpy(&v, p + 2 * c, 2); return normalized ? v / 65535.0f : v; }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t v; std::memcpy(&v, p + 4 * c, 4); return float(v); }
                case TINYGLTF_COMPONENT_TYPE_BYTE: { const float v = int8_t(p[c]); return normalized ? std::max(v / 127.0f, -1.0f) : v; }
                case TINYGLTF_COMPONENT_TYPE_SHORT: { int16_t v; std::memcpy(&v, p + 2 * c, 2); return normalized ? std::max(v / 32767.0f, -1.0f) : v; }
            }
            return 0.0f;
        }
        // An unsigned scalar's element i; callers check the component type first.
        uint32_t index(size_t i) const {
            const unsigned char* p = data + i * stride;
            switch (componentType) {
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return p[0];
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: { uint16_t v; std::memcpy(&v, p, 2); return v; }
                case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: { uint32_t v; std::memcpy(&v, p, 4); return v; }
            }
            return 0;
        }
    };

    AccessorView view(int accessorIndex, const std::string& where) const {
        const std::string at = where + ", accessor " + std::to_string(accessorIndex);
        if (accessorIndex < 0 || accessorIndex >= int(model_.accessors.size())) fail(at, "does not exist");
        const tinygltf::Accessor& a = model_.accessors[accessorIndex];
        if (a.sparse.isSparse || a.bufferView < 0) return densified(a, at);
        return denseView(a, at);
    }

    // An accessor with a buffer view, read in place.
    AccessorView denseView(const tinygltf::Accessor& a, const std::string& at) const {
        if (a.bufferView < 0 || a.bufferView >= int(model_.bufferViews.size())) fail(at, "has no valid buffer view");
        const tinygltf::BufferView& bv = model_.bufferViews[a.bufferView];
        if (bv.buffer < 0 || bv.buffer >= int(model_.buffers.size())) fail(at, "its buffer view has no valid buffer");
        const tinygltf::Buffer& buffer = model_.buffers[bv.buffer];
        const int componentBytes = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        const int components = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        if (componentBytes <= 0 || components <= 0) fail(at, "has an invalid component type or type");
        const size_t elementBytes = size_t(componentBytes) * size_t(components);
        const size_t stride = bv.byteStride ? bv.byteStride : elementBytes;
        // The last element must end inside the view, and the view inside the buffer.
        if (bv.byteOffset > buffer.data.size() || bv.byteLength > buffer.data.size() - bv.byteOffset)
            fail(at, "its buffer view runs past the end of buffer " + std::to_string(bv.buffer));
        if (a.count > 0 && (a.byteOffset > bv.byteLength ||
                            (a.count - 1) > (bv.byteLength - a.byteOffset - std::min(bv.byteLength - a.byteOffset, elementBytes)) / stride ||
                            bv.byteLength - a.byteOffset < elementBytes))
            fail(at, std::to_string(a.count) + " elements do not fit in buffer view " + std::to_string(a.bufferView));
        return {buffer.data.data() + bv.byteOffset + a.byteOffset, stride, a.count, a.componentType, components,
                a.normalized};
    }

    // A sparse accessor, or one without a buffer view (zeros), made dense (glTF 2.0 §3.6.2.3):
    // the base values (or zeros), then each sparse index's element replaced by its value. The
    // dense copy lives as long as this reader. Indices must be below the count (and, as the
    // specification requires, strictly increasing).
    AccessorView densified(const tinygltf::Accessor& a, const std::string& at) const {
        const int componentBytes = tinygltf::GetComponentSizeInBytes(uint32_t(a.componentType));
        const int components = tinygltf::GetNumComponentsInType(uint32_t(a.type));
        if (componentBytes <= 0 || components <= 0) fail(at, "has an invalid component type or type");
        const size_t elementBytes = size_t(componentBytes) * size_t(components);
        if (a.count > (size_t(1) << 32) / elementBytes) fail(at, std::to_string(a.count) + " elements are too many");
        std::vector<unsigned char>& dense = denseCopies_.emplace_back(a.count * elementBytes, 0);
        if (a.bufferView >= 0) {
            const AccessorView base = denseView(a, at);
            for (size_t i = 0; i < a.count; ++i) std::memcpy(&dense[i * elementBytes], base.data + i * base.stride, elementBytes);
        }
        if (a.sparse.isSparse) {
            const size_t n = size_t(a.sparse.count);
            if (a.sparse.count < 1 || n > a.count) fail(at, "sparse count " + std::to_string(a.sparse.count) + " is not in 1.." + std::to_string(a.count));
            const int indexType = a.sparse.indices.componentType;
            const int indexBytes = tinygltf::GetComponentSizeInBytes(uint32_t(indexType));
            if (indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                indexType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
                fail(at, "sparse indices must be unsigned bytes, shorts or ints");
            const unsigned char* indices = viewBytes(a.sparse.indices.bufferView, size_t(a.sparse.indices.byteOffset),
                                                     n * size_t(indexBytes), at + ", sparse indices");
            const unsigned char* values = viewBytes(a.sparse.values.bufferView, size_t(a.sparse.values.byteOffset),
                                                    n * elementBytes, at + ", sparse values");
            const AccessorView indexView{indices, size_t(indexBytes), n, indexType, 1, false};
            for (size_t k = 0; k < n; ++k) {
                const uint32_t i = indexView.index(k);
                if (i >= a.count) fail(at, "sparse index " + std::to_string(i) + " is past its " + std::to_string(a.count) + " elements");
                if (k > 0 && i <= indexView.index(k - 1)) fail(at, "sparse indices are not strictly increasing");
                std::memcpy(&dense[size_t(i) * elementBytes], values + k * elementBytes, elementBytes);
            }
        }
        return {dense.data(), elementBytes, a.count, a.componentType, components, a.normalized};
    }

    // `length` bytes at `offset` into a buffer view, checked to lie inside it and its buffer.
    const unsigned char* viewBytes(int bufferView, size_t offset, size_t length, const std::string& at) const {
        if (bufferView < 0 || bufferView >= int(model_.bufferViews.size())) fail(at, "has no valid buffer view");
        const tinygltf::BufferView& bv = model_.bufferViews[size_t(bufferView)];
        if (bv.buffer < 0 || bv.buffer >= int(model_.buffers.size())) fail(at, "its buffer view has no valid buffer");
        const tinygltf::Buffer& buffer = model_.buffers[size_t(bv.buffer)];
        if (bv.byteOffset > buffer.data.size() || bv.byteLength > buffer.data.size() - bv.byteOffset)
            fail(at, "its buffer view runs past the end of buffer " + std::to_string(bv.buffer));
        if (offset > bv.byteLength || length > bv.byteLength - offset)
            fail(at, std::to_string(length) + " bytes do not fit in buffer view " + std::to_string(bufferView));
        return buffer.data.data() + bv.byteOffset + offset;
    }

    // The first animation's node channels at timeSeconds_: keyframes found by binary search,
    // the time clamped to each sampler's range; STEP, LINEAR (slerp for rotations) and
    // CUBICSPLINE (Hermite over in-tangent, value, out-tangent triplets, glTF 2.0 Appendix C).
    // The animation `chosen` names (a name, or an index as a decimal number); 0 when empty.
    size_t chooseAnimation(const std::string& chosen) {
        animationChosen_ = !chosen.empty();
        if (chosen.empty()) return 0;
        for (size_t i = 0; i < model_.animations.size(); ++i)
            if (model_.animations[i].name == chosen) return i;
        size_t index = 0;
        const auto [end, ec] = std::from_chars(chosen.data(), chosen.data() + chosen.size(), index);
        if (ec == std::errc() && end == chosen.data() + chosen.size() && index < model_.animations.size()) return index;
        throw InputError(file_ + ": no animation '" + chosen + "' (" +
                         (model_.animations.empty() ? std::string("the file has none") : "it has " + animationNames()) + ")");
    }

    /// The file's animations as `0 "name", 1 "name"`, for messages.
    std::string animationNames() const {
        std::string names;
        for (size_t i = 0; i < model_.animations.size(); ++i)
            names += (i ? ", " : "") + std::to_string(i) + (model_.animations[i].name.empty() ? "" : " '" + model_.animations[i].name + "'");
        return names;
    }

    void poseAnimation() {
        if (model_.animations.empty()) return;
        const tinygltf::Animation& anim = model_.animations[animation_];
        for (size_t c = 0; c < anim.channels.size(); ++c) {
            const tinygltf::AnimationChannel& ch = anim.channels[c];
            const std::string where = "animation " + std::to_string(animation_) + " channel " + std::to_string(c);
            if (ch.target_path != "translation" && ch.target_path != "rotation" && ch.target_path != "scale" &&
                ch.target_path != "weights") {
                warnOnce("animated " + ch.target_path + " is not supported");
                continue;
            }
            if (ch.target_node < 0 || ch.target_node >= int(model_.nodes.size())) fail(where, "targets no node");
            const bool isWeights = ch.target_path == "weights";
            const int components = isWeights ? morphTargetCount(ch.target_node) : ch.target_path == "rotation" ? 4 : 3;
            if (components == 0) continue;  // weights of a mesh without targets
            if (ch.sampler < 0 || ch.sampler >= int(anim.samplers.size())) fail(where, "has no sampler");
            const tinygltf::AnimationSampler& sm = anim.samplers[ch.sampler];
            const AccessorView times = view(sm.input, where);
            const AccessorView values = view(sm.output, where);
            const bool cubic = sm.interpolation == "CUBICSPLINE";
            const size_t perKey = isWeights ? size_t(components) : 1;  // weights: scalars per key
            if (times.count == 0 || times.components != 1 || values.components != (isWeights ? 1 : components) ||
                values.count != times.count * perKey * (cubic ? 3 : 1))
                fail(where, "sampler input and output do not match");
            const std::vector<float> v = sampleChannel(times, values, sm.interpolation, components);
            if (isWeights) {
                poseWeights_[ch.target_node] = v;
                continue;
            }
            auto [it, inserted] = pose_.try_emplace(ch.target_node);
            if (inserted) it->second = restPose(model_.nodes[ch.target_node]);
            if (components == 4) it->second.rotation = glm::normalize(glm::quat(v[3], v[0], v[1], v[2]));
            else if (ch.target_path == "translation") it->second.translation = glm::vec3(v[0], v[1], v[2]);
            else it->second.scale = glm::vec3(v[0], v[1], v[2]);
        }
    }

    static NodePose restPose(const tinygltf::Node& n) {
        NodePose p;
        if (n.translation.size() == 3) p.translation = glm::vec3(n.translation[0], n.translation[1], n.translation[2]);
        if (n.rotation.size() == 4) p.rotation = glm::quat(float(n.rotation[3]), float(n.rotation[0]), float(n.rotation[1]), float(n.rotation[2]));
        if (n.scale.size() == 3) p.scale = glm::vec3(n.scale[0], n.scale[1], n.scale[2]);
        return p;
    }

    struct Keyframe {
        size_t lo, hi;  // equal when the time is clamped to an end
        float u, dt;    // position in [lo, hi] and the interval's length
    };

    Keyframe findKeyframe(const AccessorView& times) const {
        const size_t n = times.count;
        const float t = timeSeconds_;
        if (n == 1 || t <= times.get(0, 0)) return {0, 0, 0.0f, 0.0f};
        if (t >= times.get(n - 1, 0)) return {n - 1, n - 1, 0.0f, 0.0f};
        size_t lo = 0, hi = n - 1;  // times[lo] <= t < times[hi]
        while (hi - lo > 1) {
            const size_t mid = (lo + hi) / 2;
            (times.get(mid, 0) <= t ? lo : hi) = mid;
        }
        const float t0 = times.get(lo, 0), dt = times.get(hi, 0) - t0;
        return {lo, hi, dt > 0.0f ? (t - t0) / dt : 0.0f, dt};
    }

    // `width` values per key: the components of one element (vectors), or `width` consecutive
    // scalar elements (morph weights). Rotations (width 4, vectors) interpolate by slerp.
    std::vector<float> sampleChannel(const AccessorView& times, const AccessorView& values, const std::string& mode,
                                     int width) const {
        const bool cubic = mode == "CUBICSPLINE", scalars = values.components == 1 && width > 1;
        auto value = [&](size_t key, int part, int k) {  // part: 0 in-tangent, 1 value, 2 out-tangent
            const size_t element = cubic ? key * 3 + size_t(part) : key;
            return scalars ? values.get(element * size_t(width) + size_t(k), 0) : values.get(element, k);
        };
        const Keyframe f = findKeyframe(times);
        std::vector<float> out(static_cast<size_t>(width));
        const float u = f.u, u2 = u * u, u3 = u2 * u;
        for (int k = 0; k < width; ++k) {
            if (f.lo == f.hi || mode == "STEP") out[k] = value(f.lo, 1, k);
            else if (cubic)
                out[k] = (2 * u3 - 3 * u2 + 1) * value(f.lo, 1, k) + (u3 - 2 * u2 + u) * f.dt * value(f.lo, 2, k) +
                         (-2 * u3 + 3 * u2) * value(f.hi, 1, k) + (u3 - u2) * f.dt * value(f.hi, 0, k);
            else out[k] = value(f.lo, 1, k) + u * (value(f.hi, 1, k) - value(f.lo, 1, k));
        }
        if (width == 4 && !scalars && f.lo != f.hi && mode == "LINEAR") {
            const glm::quat a(value(f.lo, 1, 3), value(f.lo, 1, 0), value(f.lo, 1, 1), value(f.lo, 1, 2));
            const glm::quat b(value(f.hi, 1, 3), value(f.hi, 1, 0), value(f.hi, 1, 1), value(f.hi, 1, 2));
            const glm::quat q = glm::slerp(a, b, u);
            out = {q.x, q.y, q.z, q.w};
        }
        return out;
    }

    int morphTargetCount(int node) const {
        const int mesh = model_.nodes[node].mesh;
        if (mesh < 0 || mesh >= int(model_.meshes.size()) || model_.meshes[mesh].primitives.empty()) return 0;
        return int(model_.meshes[mesh].primitives[0].targets.size());
    }

    // Skinning (glTF 2.0 §3.7.3): a vertex's matrix is the weighted sum of its joints' matrices,
    // global(joint) x inverseBind(joint); the skinned mesh node's own transform is ignored.
    // Empty when the node has no skin or the primitive no JOINTS_0 / WEIGHTS_0.
    std::vector<glm::mat4> skinMatrices(int skinIndex, const tinygltf::Primitive& prim, size_t vertexCount,
                                        const std::string& where) const {
        const auto joints = prim.attributes.find("JOINTS_0"), weights = prim.attributes.find("WEIGHTS_0");
        if (skinIndex < 0 || joints == prim.attributes.end() || weights == prim.attributes.end()) return {};
        if (skinIndex >= int(model_.skins.size())) fail(where, "skin " + std::to_string(skinIndex) + " does not exist");
        const tinygltf::Skin& skin = model_.skins[skinIndex];
        std::vector<glm::mat4> jointMatrices(skin.joints.size(), glm::mat4(1.0f));
        const AccessorView* inverseBind = nullptr;
        AccessorView ibm{};
        if (skin.inverseBindMatrices >= 0) {
            ibm = view(skin.inverseBindMatrices, where);
            if (ibm.components != 16 || ibm.count < skin.joints.size()) fail(where, "inverse bind matrices do not match the joints");
            inverseBind = &ibm;
        }
        for (size_t j = 0; j < skin.joints.size(); ++j) {
            const int node = skin.joints[j];
            if (node < 0 || node >= int(model_.nodes.size())) fail(where, "joint " + std::to_string(j) + " is no node");
            glm::mat4 inverse(1.0f);
            if (inverseBind)
                for (int k = 0; k < 16; ++k) glm::value_ptr(inverse)[k] = inverseBind->get(j, k);
            jointMatrices[j] = globalOf(node, where) * inverse;
        }
        const AccessorView jv = view(joints->second, where), wv = view(weights->second, where);
        if (jv.components != 4 || wv.components != 4 || jv.count != vertexCount || wv.count != vertexCount)
            fail(where, "JOINTS_0 / WEIGHTS_0 do not match POSITION");
        std::vector<glm::mat4> out(vertexCount, glm::mat4(0.0f));
        for (size_t i = 0; i < vertexCount; ++i) {
            for (int k = 0; k < 4; ++k) {
                const float w = wv.get(i, k);
                if (w == 0.0f) continue;
                const float joint = jv.get(i, k);
                if (!(joint >= 0.0f) || joint >= float(jointMatrices.size()))
                    fail(where, "vertex " + std::to_string(i) + " names joint " + std::to_string(int(joint)) +
                                    " of " + std::to_string(jointMatrices.size()));
                out[i] += w * jointMatrices[size_t(joint)];
            }
        }
        return out;
    }

    // Morph target weights of a node's mesh: animated, else the node's, else the mesh's.
    std::vector<double> morphWeights(int node, const tinygltf::Mesh& mesh) const {
        if (node >= 0) {
            if (const auto it = poseWeights_.find(node); it != poseWeights_.end())
                return std::vector<double>(it->second.begin(), it->second.end());
            if (!model_.nodes[node].weights.empty()) return model_.nodes[node].weights;
        }
        return mesh.weights;
    }

    // Object-space attribute (POSITION or NORMAL) with the weighted morph target deltas added.
    std::vector<glm::vec3> morphed(const tinygltf::Primitive& prim, const AccessorView& base, const char* attribute,
                                   const std::vector<double>& weights, const std::string& where) const {
        std::vector<glm::vec3> out(base.count);
        for (size_t i = 0; i < base.count; ++i) out[i] = glm::vec3(base.get(i, 0), base.get(i, 1), base.get(i, 2));
        for (size_t t = 0; t < prim.targets.size() && t < weights.size(); ++t) {
            const float w = float(weights[t]);
            const auto it = prim.targets[t].find(attribute);
            if (w == 0.0f || it == prim.targets[t].end()) continue;
            const AccessorView d = view(it->second, where + ", morph target " + std::to_string(t));
            if (d.components != 3 || d.count != base.count) fail(where, "morph target " + std::to_string(t) + " does not match " + attribute);
            for (size_t i = 0; i < base.count; ++i) out[i] += w * glm::vec3(d.get(i, 0), d.get(i, 1), d.get(i, 2));
        }
        return out;
    }

    void addMesh(int meshIndex, const glm::mat4& world, int skinIndex, int node) {
        if (meshIndex < 0 || meshIndex >= int(model_.meshes.size())) fail("mesh " + std::to_string(meshIndex), "does not exist");
        const tinygltf::Mesh& mesh = model_.meshes[meshIndex];
        const glm::mat3 normalMatrix = glm::transpose(glm::inverse(glm::mat3(world)));
        const bool mirrored = glm::determinant(glm::mat3(world)) < 0.0f;
        for (size_t p = 0; p < mesh.primitives.size(); ++p) {
            const std::string where = "mesh " + std::to_string(meshIndex) + " primitive " + std::to_string(p);
            const tinygltf::Primitive& prim = mesh.primitives[p];
            const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
            if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN) {
                warnOnce("points and lines are skipped (" + where + ")");
                continue;
            }
            const auto position = prim.attributes.find("POSITION");
            if (position == prim.attributes.end()) fail(where, "has no POSITION");
            const AccessorView pos = view(position->second, where);
            if (pos.components != 3) fail(where, "POSITION is not a 3-vector");

            Mesh m;
            const std::vector<glm::mat4> skinned = skinMatrices(skinIndex, prim, pos.count, where);
            const std::vector<double> weights = morphWeights(node, mesh);
            if (!skinned.empty()) stats_.verticesSkinned += pos.count;
            if (std::any_of(weights.begin(), weights.end(), [](double w) { return w != 0.0; }) && !prim.targets.empty())
                stats_.verticesMorphed += pos.count;
            const std::vector<glm::vec3> objectPositions = morphed(prim, pos, "POSITION", weights, where);
            m.positions.resize(pos.count);
            for (size_t i = 0; i < pos.count; ++i) {
                const glm::mat4& toWorld = skinned.empty() ? world : skinned[i];
                m.positions[i] = glm::vec3(toWorld * glm::vec4(objectPositions[i], 1.0f));
            }
            if (const auto it = prim.attributes.find("NORMAL"); it != prim.attributes.end()) {
                const AccessorView nv = view(it->second, where);
                if (nv.components != 3 || nv.count != pos.count) fail(where, "NORMAL does not match POSITION");
                m.normals.resize(nv.count);
                const std::vector<glm::vec3> objectNormals = morphed(prim, nv, "NORMAL", weights, where);
                for (size_t i = 0; i < nv.count; ++i) {
                    const glm::vec3& in = objectNormals[i];
                    // Skinned normals use the blended matrix directly: exact for rigid joints.
                    const glm::vec3 n = skinned.empty() ? normalMatrix * in : glm::mat3(skinned[i]) * in;
                    const float len = glm::length(n);
                    m.normals[i] = len > 0.0f ? n / len : glm::vec3(0.0f, 0.0f, 1.0f);
                }
            }
            if (const auto it = prim.attributes.find("COLOR_0"); it != prim.attributes.end()) {
                const AccessorView cv = view(it->second, where);
                if ((cv.components != 3 && cv.components != 4) || cv.count != pos.count)
                    fail(where, "COLOR_0 does not match POSITION");
                m.colors.resize(cv.count);
                for (size_t i = 0; i < cv.count; ++i) m.colors[i] = glm::vec3(cv.get(i, 0), cv.get(i, 1), cv.get(i, 2));
                if (cv.components == 4) {
                    m.alphas.resize(cv.count);
                    for (size_t i = 0; i < cv.count; ++i) m.alphas[i] = cv.get(i, 3);
                }
            }

            std::vector<uint32_t> order;  // vertex indices in primitive order
            if (prim.indices >= 0) {
                const AccessorView iv = view(prim.indices, where);
                // glTF 2.0 §3.7.2.1: indices are unsigned scalars; `index` reads no other kind.
                if (iv.components != 1 || (iv.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE &&
                                           iv.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
                                           iv.componentType != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
                    fail(where + ", accessor " + std::to_string(prim.indices),
                         "indices must be unsigned byte, short or int scalars");
                order.resize(iv.count);
                for (size_t i = 0; i < iv.count; ++i) {
                    order[i] = iv.index(i);
                    if (order[i] >= pos.count)
                        fail(where, "index " + std::to_string(order[i]) + " at " + std::to_string(i) +
                                        " is out of range (" + std::to_string(pos.count) + " vertices)");
                }
            } else {
                order.resize(pos.count);
                for (size_t i = 0; i < pos.count; ++i) order[i] = uint32_t(i);
            }
            appendTriangles(mode, order, mirrored, m.indices);
            if (m.indices.empty()) continue;
            if (m.normals.empty()) computeVertexNormals(m);

            m.metallicRoughness = true;  // glTF's default material too: metallic 1, roughness 1
            m.color = glm::vec3(1.0f);
            if (prim.material >= 0 && prim.material < int(model_.materials.size()))
                addMaterial(model_.materials[prim.material], prim, pos.count, where, m);
            // KHR_materials_volume's thickness is in the mesh's units: to the world's by the node's
            // mean scale (the cube root of its volume scale), as positions were taken to the world.
            m.brdf.thickness *= std::cbrt(std::abs(glm::determinant(glm::mat3(world))));
            if ((m.textures.normal || m.textures.clearcoatNormal) && m.tangents.empty()) {
                if (const auto it = prim.attributes.find("TANGENT"); it != prim.attributes.end()) {
                    const AccessorView tv = view(it->second, where);
                    if (tv.components != 4 || tv.count != pos.count) fail(where, "TANGENT does not match POSITION");
                    m.tangents.resize(tv.count);
                    for (size_t i = 0; i < tv.count; ++i) {
                        const glm::vec3 t(tv.get(i, 0), tv.get(i, 1), tv.get(i, 2));
                        const glm::vec3 w = skinned.empty() ? glm::mat3(world) * t : glm::mat3(skinned[i]) * t;
                        const float len = glm::length(w);
                        m.tangents[i] = glm::vec4(len > 0.0f ? w / len : glm::vec3(1, 0, 0), tv.get(i, 3) < 0.0f ? -1.0f : 1.0f);
                    }
                } else {
                    computeVertexTangents(m);
                }
            }
            meshes_.push_back(std::move(m));
        }
    }

    struct TexCoordSet {
        int index = -1;  // the TEXCOORD set the mesh's texCoords hold; -1 before the first
    };

    // glTF 2.0 §3.9: factors, alpha, sidedness, unlit, and the five texture slots. All slots of
    // a primitive must read the same TEXCOORD set (a slot on another set warns and is dropped).
    void addMaterial(const tinygltf::Material& mat, const tinygltf::Primitive& prim, size_t vertexCount,
                     const std::string& where, Mesh& m) {
        const auto& pbr = mat.pbrMetallicRoughness;
        const auto& f = pbr.baseColorFactor;  // linear
        if (f.size() >= 3) m.color = glm::vec3(f[0], f[1], f[2]);
        if (f.size() >= 4) m.alpha = float(f[3]);
        if (mat.alphaMode == "MASK") m.alphaMode = raster::AlphaMode::Mask;
        if (mat.alphaMode == "BLEND") m.alphaMode = raster::AlphaMode::Blend;
        m.alphaCutoff = float(mat.alphaCutoff);
        m.doubleSided = mat.doubleSided;
        m.unlit = mat.extensions.count("KHR_materials_unlit") > 0;
        m.metallic = float(pbr.metallicFactor);
        m.roughness = float(pbr.roughnessFactor);
        if (mat.emissiveFactor.size() >= 3)
            m.emissive = glm::vec3(mat.emissiveFactor[0], mat.emissiveFactor[1], mat.emissiveFactor[2]);
        // KHR_materials_emissive_strength: the factor scaled past 1, for emitters brighter than white.
        if (const auto it = mat.extensions.find("KHR_materials_emissive_strength"); it != mat.extensions.end()) {
            const tinygltf::Value& strength = it->second.Get("emissiveStrength");
            if (strength.IsNumber()) {
                const double s = strength.GetNumberAsDouble();
                if (!(s >= 0.0) || !std::isfinite(s)) fail(where, "emissiveStrength must be a finite number, 0 or more");
                m.emissive *= float(s);
            }
        }
        // KHR_materials_ior: the dielectric reflectance the metallic-roughness BRDF starts from.
        if (const auto it = mat.extensions.find("KHR_materials_ior"); it != mat.extensions.end()) {
            const tinygltf::Value& ior = it->second.Get("ior");
            if (ior.IsNumber()) {
                const double v = ior.GetNumberAsDouble();
                if (!(v >= 1.0 || v == 0.0) || !std::isfinite(v)) fail(where, "ior must be 1 or more, or 0");
                m.ior = float(v);
            }
        }
        m.normalScale = float(mat.normalTexture.scale);
        m.occlusionStrength = float(mat.occlusionTexture.strength);
        TexCoordSet uvs;
        const auto specGloss = mat.extensions.find("KHR_materials_pbrSpecularGlossiness");
        if (m.unlit || specGloss == mat.extensions.end()) {
            m.textures.baseColor = bindTexture(pbr.baseColorTexture, "base colour", true, prim, vertexCount, where, uvs, m);
            if (m.unlit) return;  // KHR_materials_unlit reads nothing else
            m.textures.metallicRoughness =
                bindTexture(pbr.metallicRoughnessTexture, "metallic-roughness", false, prim, vertexCount, where, uvs, m);
            if (const auto it = mat.extensions.find("KHR_materials_specular"); it != mat.extensions.end())
                addDielectricSpecular(it->second, prim, vertexCount, where, uvs, m);
        } else {
            addSpecularGlossiness(specGloss->second, prim, vertexCount, where, uvs, m);
        }
        m.textures.normal = bindTexture(mat.normalTexture, "normal", false, prim, vertexCount, where, uvs, m);
        m.textures.occlusion = bindTexture(mat.occlusionTexture, "occlusion", false, prim, vertexCount, where, uvs, m);
        m.textures.emissive = bindTexture(mat.emissiveTexture, "emissive", true, prim, vertexCount, where, uvs, m);
        if (const auto it = mat.extensions.find("KHR_materials_clearcoat"); it != mat.extensions.end())
            addClearcoat(it->second, prim, vertexCount, where, uvs, m);
        if (const auto it = mat.extensions.find("KHR_materials_sheen"); it != mat.extensions.end())
            addSheen(it->second, prim, vertexCount, where, uvs, m);
        if (const auto it = mat.extensions.find("KHR_materials_transmission"); it != mat.extensions.end())
            addTransmission(mat, it->second, prim, vertexCount, where, uvs, m);
    }

    // KHR_materials_transmission: the share of the dielectric's diffuse lobe passed through (a
    // factor times the linear texture's R); zero, the default, draws the material as without it.
    // KHR_materials_volume, read with it: the thickness (a factor times the texture's G, in the
    // mesh's units: the caller scales it to the world's), the attenuation colour and distance.
    void addTransmission(const tinygltf::Material& mat, const tinygltf::Value& ext, const tinygltf::Primitive& prim,
                         size_t vertexCount, const std::string& where, TexCoordSet& uvs, Mesh& m) {
        const std::string place = where + ": KHR_materials_transmission";
        unitFactors(ext, "transmissionFactor", 0, &m.brdf.transmission, place);
        if (m.brdf.transmission == 0.0f) return;
        m.textures.transmission = bindTexture(textureInfoIn(ext, "transmissionTexture", place), "transmission", false, prim,
                                              vertexCount, where, uvs, m);
        const auto volume = mat.extensions.find("KHR_materials_volume");
        if (volume == mat.extensions.end()) return;
        const std::string volumePlace = where + ": KHR_materials_volume";
        const tinygltf::Value& v = volume->second;
        float color[3] = {1.0f, 1.0f, 1.0f};
        unitFactors(v, "thicknessFactor", 0, &m.brdf.thickness, volumePlace, double(std::numeric_limits<float>::max()));
        unitFactors(v, "attenuationColor", 3, color, volumePlace);
        m.brdf.attenuationColor = glm::vec3(color[0], color[1], color[2]);
        if (v.Has("attenuationDistance")) {
            const tinygltf::Value& d = v.Get("attenuationDistance");
            const double distance = d.IsNumber() ? d.GetNumberAsDouble() : -1.0;
            if (!(distance > 0.0) || !std::isfinite(distance)) fail(volumePlace, "attenuationDistance must be a finite number above 0");
            m.brdf.attenuationDistance = float(distance);
        }
        if (m.brdf.thickness > 0.0f)
            m.textures.thickness =
                bindTexture(textureInfoIn(v, "thicknessTexture", volumePlace), "thickness", false, prim, vertexCount, where, uvs, m);
    }

    // KHR_materials_sheen: the sheen's colour (a factor times the sRGB colour texture's RGB) and
    // roughness (a factor times the linear roughness texture's alpha). A zero colour factor
    // disables the layer, as the extension says, and then no texture of it is loaded.
    void addSheen(const tinygltf::Value& ext, const tinygltf::Primitive& prim, size_t vertexCount, const std::string& where,
                  TexCoordSet& uvs, Mesh& m) {
        const std::string place = where + ": KHR_materials_sheen";
        float color[3] = {0.0f, 0.0f, 0.0f}, roughness = 0.0f;
        unitFactors(ext, "sheenColorFactor", 3, color, place);
        unitFactors(ext, "sheenRoughnessFactor", 0, &roughness, place);
        m.brdf.sheenColor = glm::vec3(color[0], color[1], color[2]);
        m.brdf.sheenRoughness = roughness;
        if (m.brdf.sheenColor == glm::vec3(0.0f)) return;
        m.textures.sheenColor =
            bindTexture(textureInfoIn(ext, "sheenColorTexture", place), "sheen colour", true, prim, vertexCount, where, uvs, m);
        m.textures.sheenRoughness = bindTexture(textureInfoIn(ext, "sheenRoughnessTexture", place), "sheen roughness", false,
                                                prim, vertexCount, where, uvs, m);
    }

    // KHR_materials_clearcoat: the coat's weight and roughness (factors times the R and G of
    // their linear textures) and its own normal map (with its scale); without one the coat
    // follows the surface's normal before normal mapping.
    void addClearcoat(const tinygltf::Value& ext, const tinygltf::Primitive& prim, size_t vertexCount, const std::string& where,
                      TexCoordSet& uvs, Mesh& m) {
        const std::string place = where + ": KHR_materials_clearcoat";
        unitFactors(ext, "clearcoatFactor", 0, &m.brdf.clearcoat, place);
        unitFactors(ext, "clearcoatRoughnessFactor", 0, &m.brdf.clearcoatRoughness, place);
        if (m.brdf.clearcoat == 0.0f) return;  // the extension: a zero factor disables the whole layer
        m.textures.clearcoat =
            bindTexture(textureInfoIn(ext, "clearcoatTexture", place), "clearcoat", false, prim, vertexCount, where, uvs, m);
        m.textures.clearcoatRoughness = bindTexture(textureInfoIn(ext, "clearcoatRoughnessTexture", place), "clearcoat roughness",
                                                    false, prim, vertexCount, where, uvs, m);
        m.textures.clearcoatNormal = bindTexture(textureInfoIn(ext, "clearcoatNormalTexture", place), "clearcoat normal", false,
                                                 prim, vertexCount, where, uvs, m);
        if (m.textures.clearcoatNormal && ext.Get("clearcoatNormalTexture").Has("scale")) {
            const tinygltf::Value& scale = ext.Get("clearcoatNormalTexture").Get("scale");
            if (!scale.IsNumber() || !std::isfinite(scale.GetNumberAsDouble()))
                fail(place, "clearcoatNormalTexture.scale must be a finite number");
            m.brdf.clearcoatNormalScale = float(scale.GetNumberAsDouble());
        }
    }

    // KHR_materials_pbrSpecularGlossiness (archived, still exported): where a material has it,
    // it is drawn instead of pbrMetallicRoughness, as the extension's best practices ask. The
    // diffuse factor and texture take the base colour's place (linear factor, sRGB texture
    // whose alpha is coverage), the specular-glossiness texture the metallic-roughness slot
    // (sRGB specular and linear glossiness, as an sRGB texel format decodes colour and alpha).
    void addSpecularGlossiness(const tinygltf::Value& ext, const tinygltf::Primitive& prim, size_t vertexCount,
                               const std::string& where, TexCoordSet& uvs, Mesh& m) {
        const std::string place = where + ": KHR_materials_pbrSpecularGlossiness";
        float diffuse[4] = {1.0f, 1.0f, 1.0f, 1.0f}, specular[3] = {1.0f, 1.0f, 1.0f}, glossiness = 1.0f;
        unitFactors(ext, "diffuseFactor", 4, diffuse, place);
        unitFactors(ext, "specularFactor", 3, specular, place);
        unitFactors(ext, "glossinessFactor", 0, &glossiness, place);
        m.brdf.specularGlossiness = true;
        m.color = glm::vec3(diffuse[0], diffuse[1], diffuse[2]);
        m.alpha = diffuse[3];
        m.brdf.specularFactor = glm::vec3(specular[0], specular[1], specular[2]);
        m.brdf.glossiness = glossiness;
        m.textures.baseColor =
            bindTexture(textureInfoIn(ext, "diffuseTexture", place), "diffuse", true, prim, vertexCount, where, uvs, m);
        m.textures.metallicRoughness = bindTexture(textureInfoIn(ext, "specularGlossinessTexture", place), "specular-glossiness",
                                                   true, prim, vertexCount, where, uvs, m);
    }

    // KHR_materials_specular: the strength (a factor times the specular texture's alpha) and F0
    // colour (a factor, which may exceed 1, times the sRGB specular colour texture) of the
    // metallic-roughness BRDF's dielectric reflection.
    void addDielectricSpecular(const tinygltf::Value& ext, const tinygltf::Primitive& prim, size_t vertexCount,
                               const std::string& where, TexCoordSet& uvs, Mesh& m) {
        const std::string place = where + ": KHR_materials_specular";
        float strength = 1.0f, color[3] = {1.0f, 1.0f, 1.0f};
        unitFactors(ext, "specularFactor", 0, &strength, place);
        unitFactors(ext, "specularColorFactor", 3, color, place, double(std::numeric_limits<float>::max()));
        m.brdf.dielectricSpecular = true;
        m.brdf.specularStrength = strength;
        m.brdf.specularColor = glm::vec3(color[0], color[1], color[2]);
        m.textures.specular =
            bindTexture(textureInfoIn(ext, "specularTexture", place), "specular", false, prim, vertexCount, where, uvs, m);
        m.textures.specularColor = bindTexture(textureInfoIn(ext, "specularColorTexture", place), "specular colour", true, prim,
                                               vertexCount, where, uvs, m);
    }

    /// An extension's factor in [0, upper] (count 0: a single number) or array of `count` of them,
    /// into `out`; absent leaves the default there.
    void unitFactors(const tinygltf::Value& ext, const char* name, int count, float* out, const std::string& place,
                     double upper = 1.0) const {
        if (!ext.Has(name)) return;
        const tinygltf::Value& v = ext.Get(name);
        const std::string range = upper == 1.0 ? "in [0, 1]" : "finite and 0 or more";
        const std::string what = count == 0 ? std::string(name) + " must be a number " + range
                                            : std::string(name) + " must be " + std::to_string(count) + " numbers " + range;
        if (count == 0 ? !v.IsNumber() : !v.IsArray() || int(v.ArrayLen()) != count) fail(place, what);
        for (int k = 0; k < std::max(count, 1); ++k) {
            const tinygltf::Value& x = count == 0 ? v : v.Get(k);
            const double d = x.IsNumber() ? x.GetNumberAsDouble() : -1.0;
            if (!(d >= 0.0 && d <= upper)) fail(place, what);
            out[k] = float(d);
        }
    }

    /// A textureInfo inside an extension's JSON (tinygltf parses only the core ones): index,
    /// texCoord and its own extensions (KHR_texture_transform); index -1 when absent.
    tinygltf::TextureInfo textureInfoIn(const tinygltf::Value& ext, const char* name, const std::string& place) const {
        tinygltf::TextureInfo info;
        if (!ext.Has(name)) return info;
        const tinygltf::Value& v = ext.Get(name);
        const tinygltf::Value& index = v.Get("index");
        if (!v.IsObject() || !index.IsInt() || index.GetNumberAsInt() < 0 || index.GetNumberAsInt() >= int(model_.textures.size()))
            fail(place, std::string(name) + " must name a texture of the file by its index");
        info.index = index.GetNumberAsInt();
        if (v.Has("texCoord")) {
            const tinygltf::Value& set = v.Get("texCoord");
            if (!set.IsInt() || set.GetNumberAsInt() < 0) fail(place, std::string(name) + ".texCoord must be a non-negative integer");
            info.texCoord = set.GetNumberAsInt();
        }
        if (v.Has("extensions") && v.Get("extensions").IsObject()) {
            const tinygltf::Value& extensions = v.Get("extensions");
            for (const std::string& key : extensions.Keys()) info.extensions[key] = extensions.Get(key);
        }
        return info;
    }

    // One texture slot: its image (decoded once per glTF texture and colour space), its sampler,
    // its KHR_texture_transform, and the TEXCOORD set it reads, loaded into the mesh on first use.
    // A texture that cannot be used warns and the slot stays empty (the factors alone apply).
    template <class Info>
    MeshTexture bindTexture(const Info& info, const char* slot, bool srgb, const tinygltf::Primitive& prim,
                            size_t vertexCount, const std::string& where, TexCoordSet& uvs, Mesh& m) {
        if (info.index < 0) return {};
        MeshTexture bound;
        int texCoord = info.texCoord;
        bound.transform = uvTransform(info.extensions, texCoord);
        if (uvs.index >= 0 && texCoord != uvs.index) {
            warnOnce(where + ": " + slot + " texture reads TEXCOORD_" + std::to_string(texCoord) + " but another slot reads TEXCOORD_" +
                     std::to_string(uvs.index) + "; one set per primitive is supported, so it is ignored");
            return {};
        }
        const auto attribute = prim.attributes.find("TEXCOORD_" + std::to_string(texCoord));
        if (attribute == prim.attributes.end()) {
            warnOnce(where + ": " + slot + " texture without TEXCOORD_" + std::to_string(texCoord) + "; ignored");
            return {};
        }
        bound.texture = textureFor(info.index, srgb, where);
        if (!bound.texture) return {};
        if (uvs.index < 0) {
            const AccessorView uv = view(attribute->second, where);
            if (uv.components != 2 || uv.count != vertexCount) fail(where, "TEXCOORD does not match POSITION");
            m.texCoords.resize(uv.count);
            for (size_t i = 0; i < uv.count; ++i) m.texCoords[i] = glm::vec2(uv.get(i, 0), uv.get(i, 1));
            uvs.index = texCoord;
        }
        return bound;
    }

    // KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv, and an optional texCoord
    // override.
    raster::UvTransform uvTransform(const tinygltf::ExtensionMap& extensions, int& texCoord) const {
        raster::UvTransform t;
        const auto it = extensions.find("KHR_texture_transform");
        if (it == extensions.end() || !it->second.IsObject()) return t;
        const tinygltf::Value& v = it->second;
        auto pair = [&](const char* key, glm::vec2 fallback) {
            if (!v.Has(key) || !v.Get(key).IsArray() || v.Get(key).ArrayLen() < 2) return fallback;
            return glm::vec2(float(v.Get(key).Get(0).GetNumberAsDouble()), float(v.Get(key).Get(1).GetNumberAsDouble()));
        };
        const glm::vec2 offset = pair("offset", glm::vec2(0.0f)), scale = pair("scale", glm::vec2(1.0f));
        const float rotation = v.Has("rotation") ? float(v.Get("rotation").GetNumberAsDouble()) : 0.0f;
        const float c = std::cos(rotation), s = std::sin(rotation);
        const glm::mat2 rotate(c, -s, s, c);  // columns: the spec's [[c, s], [-s, c]] (rows)
        t.linear = rotate * glm::mat2(scale.x, 0.0f, 0.0f, scale.y);
        t.offset = offset;
        if (v.Has("texCoord")) texCoord = v.Get("texCoord").GetNumberAsInt();
        return t;
    }

    // Undefined filters (glTF leaves them to the implementation) are trilinear.
    static raster::TextureFilter textureFilter(const tinygltf::Sampler& s) {
        raster::TextureFilter f;
        f.magnifyNearest = s.magFilter == TINYGLTF_TEXTURE_FILTER_NEAREST;
        switch (s.minFilter) {
            case TINYGLTF_TEXTURE_FILTER_NEAREST: f.minify = raster::MinFilter::Nearest; break;
            case TINYGLTF_TEXTURE_FILTER_LINEAR: f.minify = raster::MinFilter::Linear; break;
            case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_NEAREST: f.minify = raster::MinFilter::NearestMipmapNearest; break;
            case TINYGLTF_TEXTURE_FILTER_LINEAR_MIPMAP_NEAREST: f.minify = raster::MinFilter::LinearMipmapNearest; break;
            case TINYGLTF_TEXTURE_FILTER_NEAREST_MIPMAP_LINEAR: f.minify = raster::MinFilter::NearestMipmapLinear; break;
            default: f.minify = raster::MinFilter::LinearMipmapLinear; break;
        }
        return f;
    }

    static raster::WrapMode wrapMode(int glWrap) {
        switch (glWrap) {
            case TINYGLTF_TEXTURE_WRAP_CLAMP_TO_EDGE: return raster::WrapMode::ClampToEdge;
            case TINYGLTF_TEXTURE_WRAP_MIRRORED_REPEAT: return raster::WrapMode::MirroredRepeat;
            default: return raster::WrapMode::Repeat;
        }
    }

    // Decoded once per glTF texture and colour space, shared by every primitive using it. Base
    // colour and emissive are sRGB-encoded (glTF 2.0 §3.9.2) and decoded to linear here; the
    // other slots hold linear data.
    std::shared_ptr<const raster::Texture> textureFor(int index, bool srgb, const std::string& where) {
        const auto key = std::make_pair(index, srgb);
        if (auto it = textures_.find(key); it != textures_.end()) {
            texturesUsed_.insert(key);
            return it->second;
        }
        std::shared_ptr<const raster::Texture> result;
        if (index >= int(model_.textures.size())) fail(where, "texture " + std::to_string(index) + " does not exist");
        const tinygltf::Texture& tex = model_.textures[index];
        const int source = textureSource(tex);
        const bool validImage = source >= 0 && source < int(model_.images.size());
        const tinygltf::Image* image = validImage ? &model_.images[source] : nullptr;
        const bool decoded = image && image->width > 0 && image->height > 0 && image->component >= 1 &&
                             image->component <= 4 && (image->bits == 8 || image->bits == 16) &&
                             image->image.size() == size_t(image->width) * image->height * image->component * (image->bits / 8);
        if (!decoded) {
            warnOnce("texture " + std::to_string(index) + " has no decodable image; its colour factor is used");
        } else {
            raster::WrapMode wrapU = raster::WrapMode::Repeat, wrapV = raster::WrapMode::Repeat;
            raster::TextureFilter filter;
            if (tex.sampler >= 0 && tex.sampler < int(model_.samplers.size())) {
                const tinygltf::Sampler& sampler = model_.samplers[tex.sampler];
                wrapU = wrapMode(sampler.wrapS);
                wrapV = wrapMode(sampler.wrapT);
                filter = textureFilter(sampler);
            }
            result = image->bits == 8 ? texture8(*image, srgb, wrapU, wrapV, filter)
                                      : texture16(*image, srgb, wrapU, wrapV, filter);
        }
        textures_[key] = result;
        texturesUsed_.insert(key);
        return result;
    }

    // An 8-bit image keeps its bytes (raster/texture.h): grey and grey-alpha widened to RGBA.
    static std::shared_ptr<const raster::Texture> texture8(const tinygltf::Image& image, bool srgb, raster::WrapMode wrapU,
                                                           raster::WrapMode wrapV, raster::TextureFilter filter) {
        const int c = image.component;
        const size_t count = size_t(image.width) * image.height;
        std::vector<uint8_t> rgba(count * 4);
        for (size_t i = 0; i < count; ++i) {
            const unsigned char* in = &image.image[i * c];
            uint8_t* out = &rgba[i * 4];
            out[0] = in[0];
            out[1] = c >= 3 ? in[1] : in[0];
            out[2] = c >= 3 ? in[2] : in[0];
            out[3] = c == 4 ? in[3] : (c == 2 ? in[1] : 255);
        }
        return std::make_shared<raster::Texture>(image.width, image.height, rgba,
                                                 srgb ? raster::TexelFormat::Srgb8 : raster::TexelFormat::Unorm8,
                                                 wrapU, wrapV, filter);
    }

    // A 16-bit image as linear float texels.
    static std::shared_ptr<const raster::Texture> texture16(const tinygltf::Image& image, bool srgb, raster::WrapMode wrapU,
                                                            raster::WrapMode wrapV, raster::TextureFilter filter) {
        std::vector<glm::vec4> texels(size_t(image.width) * image.height);
        const int c = image.component;
        for (size_t i = 0; i < texels.size(); ++i) {
            float v[4] = {0, 0, 0, 1};
            for (int k = 0; k < c; ++k) {
                uint16_t x;
                std::memcpy(&x, &image.image[(i * c + k) * 2], 2);
                v[k] = x / 65535.0f;
            }
            const float alpha = c == 2 ? v[1] : v[3];
            if (c <= 2) v[1] = v[2] = v[0];  // grey (+ alpha)
            texels[i] = srgb ? glm::vec4(srgbToLinear(v[0]), srgbToLinear(v[1]), srgbToLinear(v[2]), alpha)
                             : glm::vec4(v[0], v[1], v[2], alpha);
        }
        return std::make_shared<raster::Texture>(image.width, image.height, std::move(texels), wrapU, wrapV, filter);
    }

    // The image a texture reads: EXT_texture_webp's source where the texture names one (a reader
    // that has WebP takes it over the core source, which is the fallback for readers without).
    static int textureSource(const tinygltf::Texture& tex) {
        if (const auto it = tex.extensions.find("EXT_texture_webp"); it != tex.extensions.end()) {
            const tinygltf::Value& source = it->second.Get("source");
            if (source.IsInt()) return source.GetNumberAsInt();
        }
        return tex.source;
    }

    // Lists, strips (alternating order keeps the winding) and fans as triangle lists; a mirrored
    // node transform reverses each triangle so front faces stay counter-clockwise.
    static void appendTriangles(int mode, const std::vector<uint32_t>& v, bool mirrored, std::vector<uint32_t>& out) {
        auto emit = [&](uint32_t a, uint32_t b, uint32_t c) {
            if (mirrored) std::swap(b, c);
            out.insert(out.end(), {a, b, c});
        };
        if (mode == TINYGLTF_MODE_TRIANGLES)
            for (size_t i = 0; i + 2 < v.size(); i += 3) emit(v[i], v[i + 1], v[i + 2]);
        if (mode == TINYGLTF_MODE_TRIANGLE_STRIP)
            for (size_t i = 0; i + 2 < v.size(); ++i)
                i % 2 ? emit(v[i + 1], v[i], v[i + 2]) : emit(v[i], v[i + 1], v[i + 2]);
        if (mode == TINYGLTF_MODE_TRIANGLE_FAN)
            for (size_t i = 1; i + 1 < v.size(); ++i) emit(v[0], v[i], v[i + 1]);
    }

    const tinygltf::Model& model_;
    const std::string& file_;
    const WarningSink& warn_;
    std::set<std::string>& warned_;
    std::vector<Mesh> meshes_;
    std::vector<Camera> cameras_;
    std::vector<raster::Light> lights_;
    LoadStats stats_;
    TextureCache& textures_;
    std::set<std::pair<int, bool>> texturesUsed_;
    mutable std::deque<std::vector<unsigned char>> denseCopies_;  // sparse accessors made dense (view() keeps pointers)  // by this pose: its texturesDecoded
    float timeSeconds_;
    bool animationChosen_ = false;
    size_t animation_;  // the posed animation's index (0 when the file has none)
    std::map<int, NodePose> pose_;  // animated nodes
    std::map<int, std::vector<float>> poseWeights_;  // animated morph weights per node
    std::vector<glm::mat4> globals_;  // node → world, for the scene's nodes
    std::vector<int> visited_;        // the scene's nodes in traversal order
    std::vector<bool> inScene_;       // whether globals_ holds the node's transform
    std::vector<int> parents_;        // node → parent (-1: a root), for joints outside the scene
};

}  // namespace

namespace {

/// tinygltf's refusal with its place: JSON errors carry nlohmann's line and column, which in a
/// GLB count from the start of the JSON chunk (byte 20, after the 12-byte header and the chunk's
/// own 8); any other GLB refusal is about the header or the chunk table.
std::string placeOfLoadError(bool binary, const std::string& error) {
    if (error.empty()) return "not a valid glTF file";
    if (!binary) return error;
    if (error.find("parse error at line") != std::string::npos) return "JSON chunk (from byte 20): " + error;
    return "GLB header or chunk table: " + error;
}

/// The GLB container checked before tinygltf reads it (glTF 2.0, "GLB File Format
/// Specification"): the header's length within the file, and every chunk within that length.
/// tinygltf trusts a chunk's own length and copies buffers out of it, so a BIN chunk claiming
/// bytes past the end of the file would have it read past its allocation.
/// Returns "" when the container holds, else the place and the problem.
std::string glbContainerProblem(const std::string& bytes) {
    auto u32 = [&](size_t at) {
        uint32_t v;
        std::memcpy(&v, bytes.data() + at, 4);
        return v;
    };
    if (bytes.size() < 12) return "";  // tinygltf names a short header itself
    const uint64_t length = u32(8);
    if (length > bytes.size())
        return "GLB header: a length of " + std::to_string(length) + " bytes, but the file has " + std::to_string(bytes.size());
    int index = 0;
    for (uint64_t at = 12; at < length; ++index) {
        if (length - at < 8) return "GLB chunk " + std::to_string(index) + " at byte " + std::to_string(at) + ": its 8-byte header runs past the end";
        const uint64_t chunkLength = u32(size_t(at));
        const uint64_t remaining = length - at - 8;
        if (chunkLength > remaining)
            return "GLB chunk " + std::to_string(index) + " at byte " + std::to_string(at) + ": claims " + std::to_string(chunkLength) +
                   " bytes, but " + std::to_string(remaining) + " remain";
        at += 8 + chunkLength;
    }
    return "";
}

/// tinygltf's image callback: WebP (EXT_texture_webp) through libwebp as 8-bit RGBA, every other
/// format through tinygltf's own loader (stb_image: PNG, JPEG, ...).
bool loadImageData(tinygltf::Image* image, int index, std::string* error, std::string* warning, int width, int height,
                   const unsigned char* bytes, int size, void*) {
    const bool webp = size >= 12 && std::memcmp(bytes, "RIFF", 4) == 0 && std::memcmp(bytes + 8, "WEBP", 4) == 0;
    if (!webp) return tinygltf::LoadImageData(image, index, error, warning, width, height, bytes, size, nullptr);
    int w = 0, h = 0;
    uint8_t* rgba = WebPDecodeRGBA(bytes, size_t(size), &w, &h);
    if (!rgba) {
        if (error) *error += "image " + std::to_string(index) + ": not a WebP image libwebp can decode\n";
        return false;
    }
    image->width = w;
    image->height = h;
    image->component = 4;
    image->bits = 8;
    image->pixel_type = TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE;
    image->image.assign(rgba, rgba + size_t(w) * size_t(h) * 4);
    WebPFree(rgba);
    return true;
}

}  // namespace

struct GltfDocument::Parsed {
    tinygltf::Model model;
    std::string file;
    TextureCache textures;
    std::set<std::string> warned;
};

GltfDocument::GltfDocument(const std::filesystem::path& path, const WarningSink& warn) : parsed_(std::make_unique<Parsed>()) {
    const std::string file = path.string();
    parsed_->file = file;
    if (!std::filesystem::exists(path)) throw InputError(file + ": cannot open file");
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(loadImageData, nullptr);
    tinygltf::Model& model = parsed_->model;
    std::string error, warning;
    const bool binary = fileKindOf(path) == FileKind::Glb;
    bool ok = false;
    // tinygltf reports most problems through `error`, but some malformed files make it throw from
    // inside (a vector's at() on an empty list: libFuzzer's find on a GLB): those are bad input too.
    auto parse = [&](auto&& load) {
        try {
            ok = load();
        } catch (const std::bad_alloc&) {
            throw;
        } catch (const std::exception& e) {
            throw InputError(file + ": not a glTF file tinygltf can parse (" + e.what() + ")");
        }
    };
    if (binary) {
        // Read here (as LoadBinaryFromFile would) so the container is checked before tinygltf parses it.
        const std::string bytes = readFileBytes(path);
        if (bytes.size() > std::numeric_limits<uint32_t>::max())
            throw InputError(file + ": " + std::to_string(bytes.size()) + " bytes, more than a GLB can hold (its length is 32 bits)");
        if (const std::string problem = glbContainerProblem(bytes); !problem.empty()) throw InputError(file + ": " + problem);
        std::string glb = bytes;
        if (hasJsonChunk(bytes) && mentionsCompression(bytes)) glb = glbWithJson(bytes, parseableByTinygltf(glbJson(bytes)));
        parse([&] {
            return loader.LoadBinaryFromMemory(&model, &error, &warning, reinterpret_cast<const unsigned char*>(glb.data()),
                                               unsigned(glb.size()), path.parent_path().string());
        });
    } else {
        std::string json = readFileBytes(path);
        if (mentionsCompression(json)) json = parseableByTinygltf(json);
        parse([&] { return loader.LoadASCIIFromString(&model, &error, &warning, json.data(), unsigned(json.size()), path.parent_path().string()); });
    }
    if (!warning.empty()) warn(file + ": " + warning);
    if (!ok) throw InputError(file + ": " + placeOfLoadError(binary, error));
    decodeMeshoptBufferViews(model, file);
    decodeDracoPrimitives(model, file);
}

GltfDocument::GltfDocument(GltfDocument&&) noexcept = default;
GltfDocument::~GltfDocument() = default;

GltfScene GltfDocument::pose(float timeSeconds, const std::string& animation, const WarningSink& warn) const {
    return GltfReader(parsed_->model, parsed_->file, warn, timeSeconds, animation, parsed_->textures, parsed_->warned).read();
}

std::vector<std::string> GltfDocument::animationNames() const {
    std::vector<std::string> names;
    for (const tinygltf::Animation& a : parsed_->model.animations) names.push_back(a.name);
    return names;
}

GltfScene loadGltf(const std::filesystem::path& path, const WarningSink& warn, float timeSeconds,
                   const std::string& animation) {
    return GltfDocument(path, warn).pose(timeSeconds, animation, warn);
}

}  // namespace cuberille::scene
