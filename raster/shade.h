#pragma once
// Shade stage: once per pixel per primitive (multisample semantics), at the pixel centre.
//
// Perspective-correct barycentrics come from the exact edge values at the pixel centre. A
// pixel centre can lie outside the triangle when only some samples are covered; there the
// screen-space barycentrics are clamped onto the triangle before the perspective correction,
// so extrapolation cannot blow up with extreme w ratios and the weights always form a convex
// combination (no NaN or Inf can come out of finite vertex data).
//
// Each shading model is a small class the back end is instantiated with, so a model's cost is
// only what it reads.

#include <algorithm>
#include <cmath>
#include <cstdint>

#include <glm/glm.hpp>

#include "raster/draw.h"
#include "raster/environment_light.h"
#include "raster/texture.h"
#include "raster/limits.h"
#include "raster/setup.h"
#include "raster/sheen_lobe.h"
#include "raster/stats.h"
#include "raster/vertex.h"

namespace cuberille::raster {

/// Pixels of one block waiting to be shaded, as structure-of-arrays, so a shading model's loop
/// runs across pixels and the compiler vectorises it (the software counterpart of a GPU
/// shading a warp of pixels). Filled by the depth stage, read by output merge.
struct ShadeQueue {
    static constexpr int kCapacity = kBlockSizePixels * kBlockSizePixels;
    int count = 0;
    // Biased edge values at the pixel centre (each edge opposite its vertex).
    int64_t edge0[kCapacity], edge1[kCapacity], edge2[kCapacity];
    // What shade() reads of them, converted by the back end's shadeQueue in vector lanes before
    // it runs (raster/shade_queue-inl.h): the screen-space weight numerators
    // float(edge value - fill bias) at the centre, and for a shader that differences texture
    // coordinates, at the centres one pixel right (edge + A·256) and one pixel down (+ B·256).
    // One rounding from the exact integer each, as a scalar conversion rounds, so the same bits.
    float numerator[3][kCapacity];
    float numeratorRight[3][kCapacity], numeratorDown[3][kCapacity];
    uint32_t firstSample[kCapacity];  // index of the pixel's first sample in the tile
    uint32_t passMask[kCapacity];     // samples that passed the depth test
    uint32_t pixelIndex[kCapacity];   // y x image width + x: where screen-space inputs are read
    float red[kCapacity], green[kCapacity], blue[kCapacity], alpha[kCapacity];
    // Written by transmissive draws only (DrawState::transmits): the light seen through each pixel.
    float transmitRed[kCapacity], transmitGreen[kCapacity], transmitBlue[kCapacity];
};

/// The pixels of several small triangles of one tile and draw, shaded as one batch
/// (SurfaceShader::shadeAcrossTriangles). A triangle of a few pixels would fill a queue of its own
/// with one to fifteen of them, and then the shade stage's set-up (the per-vertex loads, the
/// loop's prologue and remainder) costs more than its pixels (in `field` at one sample such
/// queues ran in scalar instructions; shared, the back end runs 15% fewer: docs/performance.md).
/// GPUs pack the quads of small primitives into one warp for the same reason. Each pixel
/// carries its triangle's inputs (copied when it is queued, so the shading loop reads contiguous
/// lanes, not gathers), and output merge takes the pixels in the order they were queued, so the
/// image is the per-triangle queues' bit for bit. Only the fused one-light Lambert model (scans,
/// PLY, OBJ, the built-in scenes) shades from it so far.
struct CrossTriangleQueue {
    static constexpr int kCapacity = ShadeQueue::kCapacity;
    int count = 0;
    // The pixel's screen-space weight numerators, float(biased edge value - fill bias): the
    // conversion weightsAt() makes, made at queue time.
    float edge[3][kCapacity];
    // Its triangle's: 1 / doubled area (as float), 1 / w per vertex, and +1 or -1 for facing.
    float invArea[kCapacity], invW[3][kCapacity], facing[kCapacity];
    float normal[3][3][kCapacity];  // [vertex][component]
    float color[3][3][kCapacity];   // [vertex][component]: vertex colours or the draw's constant
    uint32_t firstSample[kCapacity];  // index of the pixel's first sample in the tile
    uint32_t passMask[kCapacity];     // samples that passed the depth test
    float red[kCapacity], green[kCapacity], blue[kCapacity];  // the result
};

/// What a triangle contributes to each of its pixels in a CrossTriangleQueue.
struct CrossTriangleInputs {
    int64_t fillBias[3];
    float invArea, invW[3], facing;
    float normal[3][3], color[3][3];  // [vertex][component]
};

/// Appends pixel `first` with its biased centre edge values; the queue must have room.
inline void queueAcrossTriangles(CrossTriangleQueue& q, const CrossTriangleInputs& in, const int64_t centreEdges[3],
                                 uint32_t first, uint32_t pass) {
    const int i = q.count++;
    for (int k = 0; k < 3; ++k) {
        q.edge[k][i] = float(centreEdges[k] - in.fillBias[k]);
        q.invW[k][i] = in.invW[k];
        for (int c = 0; c < 3; ++c) q.normal[k][c][i] = in.normal[k][c], q.color[k][c][i] = in.color[k][c];
    }
    q.invArea[i] = in.invArea;
    q.facing[i] = in.facing;
    q.firstSample[i] = first;
    q.passMask[i] = pass;
}

struct ConstantColorShader {
    static constexpr bool kShadesAcrossTriangles = false;
    static constexpr bool kInterpolatesAcrossTriangles = false;
    bool readsWeightNumerators() const { return false; }
    bool differencesTexCoords() const { return false; }
    void shade(const TriangleSetup& t, const float*, ShadeQueue& q, StageCounters&) const {
        for (int i = 0; i < q.count; ++i) {
            q.red[i] = t.flatColor.r;
            q.green[i] = t.flatColor.g;
            q.blue[i] = t.flatColor.b;
            q.alpha[i] = t.flatColor.a;
        }
    }
};

/// The surface shading models (Unlit, Lambert, MetallicRoughness), specialised at compile
/// time on the lighting model. Within a model the shader runs as passes over the whole queue
/// — weights, attributes, texture fetches, normal, lights — each a loop across pixels that
/// the compiler vectorises; a pass the draw does not need (no texture bound, no normal map,
/// no emissive) is skipped once per queue, the way a GPU's uniform branch skips a warp, never
/// tested per pixel. StageCounters records how often each effect ran.
///
/// The BRDF (MetallicRoughness, glTF 2.0 appendix B): c_diff = albedo (1 - metallic),
/// F0 = mix(dielectricF0, albedo, metallic) (0.04 unless KHR_materials_ior), alpha = roughness² (or from the
/// specular-glossiness model: BrdfExtensions::specularGlossiness; KHR_materials_specular tints and scales the
/// dielectric F0 and F90: BrdfExtensions::dielectricSpecular; KHR_materials_sheen lays a microfibre lobe over
/// it: BrdfExtensions::sheenColor; KHR_materials_clearcoat a second GGX lobe over the result:
/// BrdfExtensions::clearcoat); per light, with light intensity E
/// (pi x irradiance, see Light), E n.l ((1 - F) c_diff + pi F D V) with Schlick's F, the GGX
/// D and the height-correlated Smith V. Ambient: ambient x occlusion x (c_diff + F0), a
/// uniform environment. An environment light (Lighting::environment, image-based lighting)
/// adds occlusion x (c_diff E(n) + S(r) (F0 A + F90 B)) (raster/environment_light.h). Emissive
/// is added last.
template <ShadingModel kModel>
class SurfaceShader {
public:
    static_assert(kModel != ShadingModel::ConstantColor);
    static constexpr bool kLit = kModel != ShadingModel::Unlit;
    /// Whether the model has a CrossTriangleQueue path at all (shadesAcrossTriangles says
    /// whether this draw takes it).
    static constexpr bool kShadesAcrossTriangles = kModel == ShadingModel::Lambert;
    /// Whether the model has an InterpolatedQueue path (interpolatesAcrossTriangles says whether
    /// this draw takes it): every surface model.
    static constexpr bool kInterpolatesAcrossTriangles = true;

    SurfaceShader(const DrawState& state, const VaryingLayout& layout) : s_(state), layout_(layout) {
        hasEmissive_ = state.emissive != glm::vec3(0.0f);
        coated_ = kModel == ShadingModel::MetallicRoughness && state.brdf.clearcoat > 0.0f;
        mapsNormals_ = kLit && layout.tangent >= 0 && (state.textures.normal || (coated_ && state.textures.clearcoatNormal));
        if (kModel == ShadingModel::MetallicRoughness && state.brdf.sheenColor != glm::vec3(0.0f))
            sheenAlbedo_ = sheenAlbedoTable();
        transmissive_ = state.transmits();
        // KHR_materials_volume: ln(attenuation colour) / distance, per unit of thickness; and
        // its exponential at the factor's thickness, which is all a draw without a thickness
        // texture needs (no exp per pixel).
        const BrdfExtensions& b = state.brdf;
        volume_ = transmissive_ && b.thickness > 0.0f && std::isfinite(b.attenuationDistance) && b.attenuationColor != glm::vec3(1.0f);
        if (volume_)
            for (int k = 0; k < 3; ++k) {
                logAttenuation_[k] = std::log(b.attenuationColor[k]) / b.attenuationDistance;
                attenuation_[k] = std::exp(logAttenuation_[k] * b.thickness);
            }
        environment_ = state.lighting.environment;
        if (environment_) environmentSh_ = &environment_->irradianceHarmonics(state.lighting.environmentLessDominantLight);
        fusedLambert_ = kModel == ShadingModel::Lambert && state.lighting.lightCount == 1 && !environment_ &&
                        state.lighting.lights[0].type == LightType::Directional &&
                        state.lighting.lights[0].visibility == nullptr && state.lighting.ambientVisibility == nullptr &&
                        layout.texCoord < 0 && layout.alpha < 0 && !hasEmissive_;
    }

    void shade(const TriangleSetup& t, const float* v, ShadeQueue& q, StageCounters& counters) const {
        if constexpr (kModel == ShadingModel::Lambert) {
            if (fusedLambert_) return lambertOneDirectionalLight(t, v, q, counters);
        }
        PixelAttributes a;
        interpolateAttributes(t, v, q, 0, a, counters);
        shadeInterpolated(q, a, counters);
    }

private:
    static constexpr int N = ShadeQueue::kCapacity;
    static_assert(N <= SampleFootprints::kMaxPoints, "a queue's texture footprints are planned in one SampleFootprints");

    /// Per-pixel values of the queue, structure-of-arrays.
    struct PixelAttributes {
        float w[3][N];           // perspective-correct barycentrics
        float albedo[3][N];      // linear RGB
        float alpha[1][N];
        float uv[2][N], dUVdx[2][N], dUVdy[2][N];
        float normal[3][N];      // world space, unit length
        // Normal-mapped draws only: the interpolated tangent and handedness, and the sign that
        // turns the pixel's normal to the viewer (its triangle's), for the second half, which
        // perturbs and turns the normal (a queue may hold several triangles' pixels).
        float tangent[4][N];
        float facing[N];
        float position[3][N];    // world space
        float radiance[3][N];    // the result
        // KHR_materials_clearcoat only: the coat's normal (its own normal map's, or the surface's
        // before normal mapping), its weight clearcoat x Fresnel(n_c.v), and its radiance.
        float coatNormal[3][N];
        float coatWeight[N];
        float coatRadiance[3][N];
        // KHR_materials_transmission only: the light seen through, per channel.
        float transmit[3][N];
        // The last texture coordinates fetched (fetchAll): glTF's slots mostly share one
        // size and one transform, and then share the transformed UVs and the level of detail.
        struct FetchCoordinates {
            int width = 0, height = 0;  // 0: none fetched yet (a texture is at least 1x1)
            UvTransform transform;
            float u[N], v[N], lod[N];
            // Where those coordinates sample the last 8-bit texture layout planned: the
            // material's textures of one size, wraps and filter gather from the same places.
            SampleFootprints footprints;
        } fetched;
    };

    /// One filtered texel per queued pixel, a channel per array.
    struct FetchedTexels {
        float r[N], g[N], b[N], a[N];
    };

public:
    /// The pixels of several small triangles of one tile and draw, shaded as one queue in two
    /// halves: each triangle interpolates its attributes into its range of the queue when its
    /// pixels have been queued (interpolateAttributes, the half that reads the triangle), and
    /// the lights run across the whole queue when it is full or the tile ends (shadeInterpolated,
    /// the half that reads only the pixels, texture fetches included). Every model and material
    /// but the fused Lambert one, which has CrossTriangleQueue (interpolatesAcrossTriangles). A
    /// normal map's tangent frame is per pixel like every other attribute: the first half keeps
    /// each pixel's tangent and facing sign, the second fetches the map and turns the normal. The
    /// same arithmetic per pixel as a queue of one triangle's pixels, and a texture's sample at a
    /// point does not depend on the other points of its batch, so the same bits.
    struct InterpolatedQueue {
        ShadeQueue pixels;            // numerators, firstSample, passMask, pixelIndex; then the colours
        PixelAttributes attributes;  // written triangle by triangle, lit as one queue
        /// After a queue is lit: the next one's texture coordinates are others.
        void forgetFetches() { attributes.fetched.width = 0; }
    };

    /// Whether this draw's triangles may share an InterpolatedQueue: every draw but a fused
    /// Lambert one.
    bool interpolatesAcrossTriangles() const { return !fusedLambert_; }

    /// The half of shade() that reads the triangle, for queue pixels [begin, q.count): the
    /// perspective weights and the attributes they interpolate, the texture coordinates and
    /// their derivatives, the unit normals facing the viewer (normal-mapped: the normals as
    /// interpolated, with the tangents and facing signs the second half needs). What it writes
    /// to `a` is per pixel.
    void interpolateAttributes(const TriangleSetup& t, const float* v, const ShadeQueue& q, int begin, PixelAttributes& a,
                               StageCounters& counters) const {
        const int end = q.count;
        perspectiveWeights(t, q, begin, end, a);
        if (layout_.color >= 0)
            interpolate<3>(v, layout_.color, begin, end, a.w, a.albedo);
        else
            for (int k = 0; k < 3; ++k) std::fill(a.albedo[k] + begin, a.albedo[k] + end, s_.constantColor[k]);
        if (layout_.alpha >= 0)
            interpolate<1>(v, layout_.alpha, begin, end, a.w, a.alpha);
        else
            std::fill(a.alpha[0] + begin, a.alpha[0] + end, s_.constantColor.a);
        counters.varyingsInterpolated += uint64_t(end - begin) * layout_.count;
        if (layout_.texCoord >= 0) texCoordsAndDerivatives(t, v, q, begin, end, a);
        if constexpr (kLit) {
            shadingNormals(t, v, begin, end, a);
            if (layout_.position >= 0) interpolate<3>(v, layout_.position, begin, end, a.w, a.position);
        }
    }

    /// The half of shade() that reads only the pixels' attributes and the draw: the normal map
    /// and the normals' facing, the other textures, occlusion, the shading model's lights,
    /// emission, a coat, and the colours written to the queue. Texture fetches plan the queue's
    /// footprints once (PixelAttributes::fetched): `a` is a fresh one, or forgetFetches() was
    /// called after its last queue.
    void shadeInterpolated(ShadeQueue& q, PixelAttributes& a, StageCounters& counters) const {
        if constexpr (kLit) {
            if (mapsNormals_) mappedNormals(q.count, a, counters);
        }
        if (layout_.texCoord >= 0 && s_.textures.baseColor) applyBaseColorTexture(q.count, a, counters);
        if constexpr (!kLit) {
            writeOut(q, a.albedo, a.alpha);
        } else {
            const bool textured = layout_.texCoord >= 0;
            float occlusion[ShadeQueue::kCapacity];
            std::fill_n(occlusion, q.count, 1.0f);
            if (textured && s_.textures.occlusion) occlusionFromTexture(q.count, a, occlusion, counters);
            if (const float* open = s_.lighting.ambientVisibility)
                for (int i = 0; i < q.count; ++i) occlusion[i] *= open[q.pixelIndex[i]];
            if constexpr (kModel == ShadingModel::Lambert)
                lambert(q, a, occlusion, counters);
            else
                metallicRoughness(q, a, occlusion, counters);
            if (hasEmissive_) addEmissive(q.count, a, counters);
            if (coated_) underTheCoat(q.count, a, transmissive_);
            writeOut(q, a.radiance, a.alpha);
            if (transmissive_) writeTransmittance(q, a);
        }
    }

private:

    // Perspective-correct weights of queued pixel i: screen weights clamped onto the triangle
    // (so the result is always a convex combination), times 1/w, renormalised. Shared by the
    // passes and the fused Lambert loop, so both compute the same weights.
    struct Weights {
        float w0, w1, w2;
    };
    [[gnu::always_inline]] static Weights weightsAt(const TriangleSetup& t, const ShadeQueue& q, int i) {
        return weightsOf(q.numerator[0][i], q.numerator[1][i], q.numerator[2][i], float(t.invDoubleArea), t.invW[0],
                         t.invW[1], t.invW[2]);
    }
    /// The weights from the screen-space numerators e_k (edge value less fill bias, as float).
    [[gnu::always_inline]] static Weights weightsOf(float e0, float e1, float e2, float invArea, float invW0, float invW1,
                                                    float invW2) {
        const float q0 = std::max(0.0f, e0 * invArea) * invW0;
        const float q1 = std::max(0.0f, e1 * invArea) * invW1;
        const float q2 = std::max(0.0f, e2 * invArea) * invW2;
        const float norm = 1.0f / (q0 + q1 + q2);
        return {q0 * norm, q1 * norm, q2 * norm};
    }

    static void perspectiveWeights(const TriangleSetup& t, const ShadeQueue& q, int begin, int end, PixelAttributes& a) {
        for (int i = begin; i < end; ++i) {
            const Weights w = weightsAt(t, q, i);
            a.w[0][i] = w.w0, a.w[1][i] = w.w1, a.w[2][i] = w.w2;
        }
    }

    template <int kComponents>
    [[gnu::always_inline]] void interpolate(const float* v, int offset, int begin, int end, const float (&w)[3][N],
                                            float (*out)[N]) const {
        const int n = layout_.count;
        for (int k = 0; k < kComponents; ++k) {
            const float v0 = v[offset + k], v1 = v[n + offset + k], v2 = v[2 * n + offset + k];
            for (int i = begin; i < end; ++i) out[k][i] = w[0][i] * v0 + w[1][i] * v1 + w[2][i] * v2;
        }
    }

    // Texture coordinates and their exact derivatives: the perspective-correct UV is also
    // evaluated one pixel right and one pixel down, from the same edge functions stepped by
    // A·256 and B·256, and differenced (per pixel, where a GPU differences across a 2x2 quad).
    // Those neighbours use unclamped weights, which like a GPU's helper pixels extrapolate the
    // attribute plane past the triangle's edges (clamping would bend it there); a degenerate
    // extrapolation gives NaN, which the level of detail treats as level 0.
    void texCoordsAndDerivatives(const TriangleSetup& t, const float* v, const ShadeQueue& q, int begin, int end,
                                 PixelAttributes& a) const {
        interpolate<2>(v, layout_.texCoord, begin, end, a.w, a.uv);
        const int n = layout_.count, o = layout_.texCoord;
        const float invArea = float(t.invDoubleArea);
        // The division is made whatever the sum, and its result kept only where the sum is
        // positive, so the loop has no branch and vectorises.
        auto uvAt = [&](const float (&numerator)[3][N], int i) {
            const float q0 = numerator[0][i] * invArea * t.invW[0];
            const float q1 = numerator[1][i] * invArea * t.invW[1];
            const float q2 = numerator[2][i] * invArea * t.invW[2];
            const float sum = q0 + q1 + q2;
            const float reciprocal = 1.0f / sum;
            const float norm = sum > 0.0f ? reciprocal : NAN;
            return glm::vec2(q0 * v[o] + q1 * v[n + o] + q2 * v[2 * n + o],
                             q0 * v[o + 1] + q1 * v[n + o + 1] + q2 * v[2 * n + o + 1]) * norm;
        };
        for (int i = begin; i < end; ++i) {
            const glm::vec2 plane = uvAt(q.numerator, i);
            const glm::vec2 right = uvAt(q.numeratorRight, i);
            const glm::vec2 down = uvAt(q.numeratorDown, i);
            a.dUVdx[0][i] = right.x - plane.x, a.dUVdx[1][i] = right.y - plane.y;
            a.dUVdy[0][i] = down.x - plane.x, a.dUVdy[1][i] = down.y - plane.y;
        }
    }

    // One filtered fetch per pixel through the binding's UV transform (applied to the
    // derivatives too, so the level of detail follows the transformed coordinates), for the
    // whole queue at once (Texture::sampleBatch overlaps the texel reads of its pixels).
    static void fetchAll(const TextureBinding& b, PixelAttributes& a, int count, FetchedTexels& out) {
        typename PixelAttributes::FetchCoordinates& c = a.fetched;
        const Texture& t = *b.texture;
        if (c.width != t.width() || c.height != t.height() || c.transform.linear != b.transform.linear ||
            c.transform.offset != b.transform.offset) {
            const glm::mat2& m = b.transform.linear;
            for (int i = 0; i < count; ++i) {
                const glm::vec2 uv = b.transform.apply({a.uv[0][i], a.uv[1][i]});
                const glm::vec2 dx = m * glm::vec2(a.dUVdx[0][i], a.dUVdx[1][i]);
                const glm::vec2 dy = m * glm::vec2(a.dUVdy[0][i], a.dUVdy[1][i]);
                c.u[i] = uv.x, c.v[i] = uv.y, c.lod[i] = t.footprintTexels(dx, dy);
            }
            for (int i = 0; i < count; ++i) c.lod[i] = Texture::levelOfFootprint(c.lod[i]);  // log2: a call per pixel
            c.width = t.width(), c.height = t.height(), c.transform = b.transform;
            c.footprints.clear();
        }
        t.sampleBatch(count, c.u, c.v, c.lod, {out.r, out.g, out.b, out.a}, c.footprints);
    }

    void applyBaseColorTexture(int count, PixelAttributes& a, StageCounters& counters) const {
        FetchedTexels texels;
        fetchAll(s_.textures.baseColor, a, count, texels);
        for (int i = 0; i < count; ++i) {
            a.albedo[0][i] *= texels.r[i], a.albedo[1][i] *= texels.g[i], a.albedo[2][i] *= texels.b[i];
            a.alpha[0][i] *= texels.a[i];
        }
        counters.textureSamples += uint64_t(count);
    }

    // Unit world-space normals: interpolated, perturbed by the normal map when there is one,
    // and reversed on back faces (glTF 2.0 §3.9.3, double-sided materials). A normal-mapped
    // draw's are finished in the second half (mappedNormals).
    void shadingNormals(const TriangleSetup& t, const float* v, int begin, int end, PixelAttributes& a) const {
        interpolate<3>(v, layout_.normal, begin, end, a.w, a.normal);
        const bool coatNormal = coated_ && layout_.tangent >= 0;  // else the coat follows a.normal
        if (coatNormal)
            for (int k = 0; k < 3; ++k) std::copy(a.normal[k] + begin, a.normal[k] + end, a.coatNormal[k] + begin);
        const float facing = t.backFacing ? -1.0f : 1.0f;
        if (mapsNormals_) {
            interpolate<4>(v, layout_.tangent, begin, end, a.w, a.tangent);
            std::fill(a.facing + begin, a.facing + end, facing);
            return;
        }
        const auto triangleFacing = [facing](int) { return facing; };
        unitFacing(begin, end, triangleFacing, a.normal);
        if (coatNormal) unitFacing(begin, end, triangleFacing, a.coatNormal);
    }

    // The normals of a normal-mapped draw, for the whole queue: perturbed by the maps (normal
    // maps are textures: only a draw with texture coordinates has them), then unit length and
    // turned by each pixel's facing sign, as shadingNormals turns an unmapped draw's.
    void mappedNormals(int count, PixelAttributes& a, StageCounters& counters) const {
        const bool coatNormal = coated_;  // mapsNormals_ implies tangents
        if (s_.textures.normal) normalMapped(s_.textures.normal, s_.normalScale, a.tangent, count, a, a.normal, counters);
        if (coatNormal && s_.textures.clearcoatNormal)
            normalMapped(s_.textures.clearcoatNormal, s_.brdf.clearcoatNormalScale, a.tangent, count, a, a.coatNormal, counters);
        const auto pixelFacing = [&a](int i) { return a.facing[i]; };
        unitFacing(0, count, pixelFacing, a.normal);
        if (coatNormal) unitFacing(0, count, pixelFacing, a.coatNormal);
    }

    // `normal` perturbed by a tangent-space normal map, in the frame of the interpolated tangent
    // (made orthogonal to the normal) and its bitangent.
    void normalMapped(const TextureBinding& map, float scale, const float (&tangent)[4][N], int count, PixelAttributes& a,
                      float (&normal)[3][N], StageCounters& counters) const {
        FetchedTexels texels;
        fetchAll(map, a, count, texels);
        for (int i = 0; i < count; ++i) {
            const glm::vec3 nrm = safeNormalize({normal[0][i], normal[1][i], normal[2][i]});
            glm::vec3 tan(tangent[0][i], tangent[1][i], tangent[2][i]);
            tan = safeNormalize(tan - nrm * glm::dot(nrm, tan));  // Gram-Schmidt
            const glm::vec3 bitangent = glm::cross(nrm, tan) * (tangent[3][i] < 0.0f ? -1.0f : 1.0f);
            const glm::vec3 m(scale * (2.0f * texels.r[i] - 1.0f), scale * (2.0f * texels.g[i] - 1.0f), 2.0f * texels.b[i] - 1.0f);
            const glm::vec3 n = tan * m.x + bitangent * m.y + nrm * m.z;
            normal[0][i] = n.x, normal[1][i] = n.y, normal[2][i] = n.z;
        }
        counters.textureSamples += uint64_t(count);
    }

    /// Normals [begin, end) to unit length, each times facingAt(i), its pixel's sign: the
    /// triangle's for a queue range (shadingNormals), each pixel's own over a normal-mapped queue
    /// (mappedNormals). A zero normal stays zero.
    template <class FacingAt>
    static void unitFacing(int begin, int end, FacingAt facingAt, float (&normal)[3][N]) {
        for (int i = begin; i < end; ++i) {
            const float x = normal[0][i], y = normal[1][i], z = normal[2][i];
            const float len2 = x * x + y * y + z * z;
            const float inv = len2 > 0.0f ? facingAt(i) / std::sqrt(len2) : 0.0f;
            normal[0][i] = x * inv, normal[1][i] = y * inv, normal[2][i] = z * inv;
        }
    }

    void occlusionFromTexture(int count, PixelAttributes& a, float* occlusion, StageCounters& counters) const {
        const float strength = s_.occlusionStrength;
        FetchedTexels texels;
        fetchAll(s_.textures.occlusion, a, count, texels);
        for (int i = 0; i < count; ++i) occlusion[i] = 1.0f + strength * (texels.r[i] - 1.0f);
        counters.textureSamples += uint64_t(count);
    }

    // Direction to the light and the intensity arriving, at one pixel.
    struct Incident {
        glm::vec3 toLight;
        glm::vec3 intensity;
    };
    static Incident incident(const Light& light, const PixelAttributes& a, int i) {
        if (light.type == LightType::Directional) return {-light.direction, light.intensity};
        const glm::vec3 d = light.position - glm::vec3(a.position[0][i], a.position[1][i], a.position[2][i]);
        const float distance2 = std::max(glm::dot(d, d), 1e-12f);
        const glm::vec3 l = d / std::sqrt(distance2);
        float attenuation = 1.0f / distance2;
        if (light.range > 0.0f) {  // KHR_lights_punctual's recommended smooth cut-off
            const float r = distance2 / (light.range * light.range);
            const float window = std::clamp(1.0f - r * r, 0.0f, 1.0f);
            attenuation *= window * window;
        }
        if (light.type == LightType::Spot) {
            const float scale = 1.0f / std::max(0.001f, light.cosInnerCone - light.cosOuterCone);
            const float cone = std::clamp((glm::dot(light.direction, -l) - light.cosOuterCone) * scale, 0.0f, 1.0f);
            attenuation *= cone * cone;
        }
        return {l, light.intensity * attenuation};
    }

    // The light's shadow mask at each queued pixel, gathered before a light's pass so the pass has
    // no branch on it: 1 where the light has none (a product with 1 is exact, so an unshadowed
    // light shades as if it were not multiplied in).
    static void shadowMask(const Light& light, const ShadeQueue& q, float* out) {
        if (light.visibility)
            for (int i = 0; i < q.count; ++i) out[i] = light.visibility[q.pixelIndex[i]];
        else
            std::fill_n(out, q.count, 1.0f);
    }

    // The common case (scans, PLY and OBJ models, the built-in scenes: one directional light,
    // no textures, no vertex alpha, no emissive) fused into one loop that never leaves
    // registers. The same arithmetic as the passes (weights, interpolation, normalised n.l), so
    // the result agrees with them up to rounding.
    void lambertOneDirectionalLight(const TriangleSetup& t, const float* v, ShadeQueue& q,
                                    StageCounters& counters) const {
        // Per-vertex values in locals: the queue's stores could alias `v` as far as the
        // compiler knows, and would force a reload of all 18 every pixel.
        CrossTriangleInputs in;
        triangleInputs(t, v, in);
        const FusedLambertLight light = fusedLambertLight();
        const float alpha = fusedLambertAlpha();
        for (int i = 0; i < q.count; ++i) {
            const Weights w = weightsAt(t, q, i);
            const glm::vec3 c = fusedLambertAt(w, in.normal, in.color, in.facing, light);
            q.red[i] = c.r, q.green[i] = c.g, q.blue[i] = c.b;
            q.alpha[i] = alpha;
        }
        counters.varyingsInterpolated += uint64_t(q.count) * layout_.count;
        counters.lightEvaluations += uint64_t(q.count);
    }

public:
    /// Whether this draw's small triangles may share a CrossTriangleQueue: the fused Lambert
    /// model, whose per-triangle inputs are CrossTriangleInputs.
    bool shadesAcrossTriangles() const { return fusedLambert_; }

    /// What shade() reads of a ShadeQueue's converted edge values: the weight numerators always,
    /// the stepped ones where a texture's level of detail needs the coordinates' derivatives.
    bool readsWeightNumerators() const { return true; }
    bool differencesTexCoords() const { return layout_.texCoord >= 0; }

    /// A triangle's inputs to the fused Lambert model (shadesAcrossTriangles draws).
    void triangleInputs(const TriangleSetup& t, const float* v, CrossTriangleInputs& in) const {
        const int n = layout_.count, on = layout_.normal, oc = layout_.color;
        for (int k = 0; k < 3; ++k) {
            in.fillBias[k] = t.fillBias[k];
            in.invW[k] = t.invW[k];
            for (int c = 0; c < 3; ++c)
                in.normal[k][c] = v[k * n + on + c], in.color[k][c] = oc >= 0 ? v[k * n + oc + c] : s_.constantColor[c];
        }
        in.invArea = float(t.invDoubleArea);
        in.facing = t.backFacing ? -1.0f : 1.0f;
    }

    /// The fused Lambert model over a CrossTriangleQueue: the loop of lambertOneDirectionalLight
    /// with each pixel's triangle inputs read from its lanes, so the same bits per pixel.
    void shadeAcrossTriangles(CrossTriangleQueue& q, StageCounters& counters) const {
        const FusedLambertLight light = fusedLambertLight();
        for (int i = 0; i < q.count; ++i) {
            const Weights w = weightsOf(q.edge[0][i], q.edge[1][i], q.edge[2][i], q.invArea[i], q.invW[0][i], q.invW[1][i],
                                        q.invW[2][i]);
            float normal[3][3], color[3][3];
            for (int k = 0; k < 3; ++k)
                for (int c = 0; c < 3; ++c) normal[k][c] = q.normal[k][c][i], color[k][c] = q.color[k][c][i];
            const glm::vec3 c = fusedLambertAt(w, normal, color, q.facing[i], light);
            q.red[i] = c.r, q.green[i] = c.g, q.blue[i] = c.b;
        }
        counters.varyingsInterpolated += uint64_t(q.count) * layout_.count;
        counters.lightEvaluations += uint64_t(q.count);
    }

    /// The alpha every pixel of a fused Lambert draw shades to.
    float fusedLambertAlpha() const { return s_.constantColor.a; }

private:
    struct FusedLambertLight {
        glm::vec3 direction, intensity, ambient;  // direction: towards the light
    };
    FusedLambertLight fusedLambertLight() const {
        const Light& light = s_.lighting.lights[0];
        return {-light.direction, light.intensity, s_.lighting.ambient};
    }

    /// One pixel of the fused Lambert model: the normal and colour interpolated, n.l with the
    /// normal reversed on back faces (facing -1), normalised by the normal's length.
    [[gnu::always_inline]] static glm::vec3 fusedLambertAt(const Weights& w, const float (&normal)[3][3],
                                                           const float (&color)[3][3], float facing,
                                                           const FusedLambertLight& light) {
        const glm::vec3 l = light.direction * facing, e = light.intensity, amb = light.ambient;
        auto lerp = [&](const float(&x)[3][3], int c) { return w.w0 * x[0][c] + w.w1 * x[1][c] + w.w2 * x[2][c]; };
        const float nx = lerp(normal, 0), ny = lerp(normal, 1), nz = lerp(normal, 2);
        const float len2 = nx * nx + ny * ny + nz * nz;
        const float nDotL = nx * l.x + ny * l.y + nz * l.z;
        const float cosine = len2 > 0.0f ? std::max(0.0f, nDotL) / std::sqrt(len2) : 0.0f;
        return {lerp(color, 0) * (amb.x + e.x * cosine), lerp(color, 1) * (amb.y + e.y * cosine),
                lerp(color, 2) * (amb.z + e.z * cosine)};
    }

    void lambert(const ShadeQueue& q, PixelAttributes& a, const float* occlusion, StageCounters& counters) const {
        const int count = q.count;
        const Lighting& lighting = s_.lighting;
        float irradiance[3][N];
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < count; ++i) irradiance[k][i] = lighting.ambient[k] * occlusion[i];
        for (int l = 0; l < lighting.lightCount; ++l) {
            const Light& light = lighting.lights[l];
            float shadowed[N];
            shadowMask(light, q, shadowed);
            if (light.type == LightType::Directional) {  // the common case, vectorised
                const glm::vec3 d = -light.direction, e = light.intensity;
                for (int i = 0; i < count; ++i) {
                    const float c = std::max(0.0f, a.normal[0][i] * d.x + a.normal[1][i] * d.y + a.normal[2][i] * d.z);
                    const float v = shadowed[i];
                    irradiance[0][i] += e.x * c * v, irradiance[1][i] += e.y * c * v, irradiance[2][i] += e.z * c * v;
                }
            } else {
                for (int i = 0; i < count; ++i) {
                    const Incident in = incident(light, a, i);
                    float c = std::max(0.0f, glm::dot(glm::vec3(a.normal[0][i], a.normal[1][i], a.normal[2][i]), in.toLight));
                    c *= shadowed[i];
                    for (int k = 0; k < 3; ++k) irradiance[k][i] += in.intensity[k] * c;
                }
            }
        }
        counters.lightEvaluations += uint64_t(count) * lighting.lightCount;
        if (environment_) {
            environmentIrradiance(count, a, occlusion, irradiance);
            counters.environmentPixels += uint64_t(count);
        }
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < count; ++i) a.radiance[k][i] = a.albedo[k][i] * irradiance[k][i];
    }

    /// What the BRDF needs at each pixel besides the normal and the lights.
    struct SurfaceAtPixels {
        float alpha2[N], nDotV[N];
        float diffuse[3][N], f0[3][N], view[3][N];
        float f90[N];  // with KHR_materials_specular only; 1 otherwise, and not stored
        float roughness[N];  // perceptual, floored: what the environment's levels are indexed by
        float irradiance[3][N];  // the environment's E(n), floored at 0: written by addEnvironment, read by the sheen
    };

    // Two passes, each a loop across the queue the compiler vectorises (a light's type, range
    // and shadow mask are uniform across it): the material and view at each pixel, then each
    // light's term added in light order, as one pixel at a time would add them.
    void metallicRoughness(const ShadeQueue& q, PixelAttributes& a, const float* occlusion,
                           StageCounters& counters) const {
        const int count = q.count;
        const Lighting& lighting = s_.lighting;
        const bool textured = layout_.texCoord >= 0 && s_.textures.metallicRoughness;
        FetchedTexels texels;
        if (textured) {
            fetchAll(s_.textures.metallicRoughness, a, count, texels);
        } else {  // factors times 1, exactly the factors: one loop, without a branch in it
            std::fill_n(texels.g, count, 1.0f);
            std::fill_n(texels.b, count, 1.0f);
            if (s_.brdf.specularGlossiness) std::fill_n(texels.r, count, 1.0f), std::fill_n(texels.a, count, 1.0f);
        }
        SurfaceAtPixels m;
        const bool withF90 = s_.brdf.dielectricSpecular && !s_.brdf.specularGlossiness;
        if (s_.brdf.specularGlossiness) {
            specularGlossinessMaterial(count, a, occlusion, texels, m);
            counters.specularGlossinessPixels += uint64_t(count);
        } else if (withF90) {
            dielectricSpecularMaterial(count, a, occlusion, texels, m, counters);
            counters.dielectricSpecularPixels += uint64_t(count);
        } else {
            metallicRoughnessMaterial(count, a, occlusion, texels, m);
        }
        if (transmissive_) transmissionMaterial(count, a, occlusion, m, withF90, counters);
        for (int l = 0; l < lighting.lightCount; ++l) {
            const Light& light = lighting.lights[l];
            const bool directional = light.type == LightType::Directional;
            if (withF90)
                directional ? addLight<true, true>(light, q, a, m) : addLight<false, true>(light, q, a, m);
            else
                directional ? addLight<true, false>(light, q, a, m) : addLight<false, false>(light, q, a, m);
        }
        counters.lightEvaluations += uint64_t(count) * lighting.lightCount;
        if (environment_) {
            withF90 ? addEnvironment<true>(count, a, occlusion, m) : addEnvironment<false>(count, a, occlusion, m);
            counters.environmentPixels += uint64_t(count);
        }
        if (textured) counters.textureSamples += uint64_t(count);
        if (sheenAlbedo_) sheen(q, a, occlusion, m, counters);
        if (coated_) clearcoat(q, a, occlusion, m, counters);
    }

    // KHR_materials_transmission: a share t (factor x the texture's R) of the dielectric's diffuse
    // lobe becomes light passed through — the transmittance t c_diff (1 - F(n.v)), the base colour
    // tinting it, Schlick's F at the view as the reflection takes its share — and the diffuse lobe
    // and its ambient keep 1 - t. With KHR_materials_volume, over thickness d the transmittance is
    // attenuated by attenuationColor^(d / attenuationDistance). Before the lights, which then
    // light the reduced c_diff; the layers above (sheen, coat) dim the transmittance as they dim
    // the material.
    [[gnu::noinline]] void transmissionMaterial(int count, PixelAttributes& a, const float* occlusion, SurfaceAtPixels& m, bool withF90,
                                                StageCounters& counters) const {
        FetchedTexels share, thickness;
        fetchOrOnes(s_.textures.transmission, count, a, share, counters);
        const bool thicknessTexture = volume_ && layout_.texCoord >= 0 && s_.textures.thickness;
        if (thicknessTexture) fetchOrOnes(s_.textures.thickness, count, a, thickness, counters);
        for (int i = 0; i < count; ++i) {
            const float t = std::clamp(s_.brdf.transmission * share.r[i], 0.0f, 1.0f);
            const float schlick = pow5(1.0f - m.nDotV[i]), f90 = withF90 ? m.f90[i] : 1.0f;
            glm::vec3 attenuation(1.0f);
            if (thicknessTexture) {
                const float d = s_.brdf.thickness * thickness.g[i];  // 0: thin-walled there
                for (int k = 0; k < 3; ++k) attenuation[k] = d > 0.0f ? std::exp(logAttenuation_[k] * d) : 1.0f;
            } else if (volume_) {
                attenuation = glm::vec3(attenuation_[0], attenuation_[1], attenuation_[2]);
            }
            for (int k = 0; k < 3; ++k) {
                const float fresnel = m.f0[k][i] + (f90 - m.f0[k][i]) * schlick;
                a.transmit[k][i] = t * m.diffuse[k][i] * (1.0f - fresnel) * attenuation[k];
                m.diffuse[k][i] *= 1.0f - t;
                a.radiance[k][i] = s_.lighting.ambient[k] * occlusion[i] * (m.diffuse[k][i] + m.f0[k][i]);
            }
        }
        counters.transmissionPixels += uint64_t(count);
    }

    static void writeTransmittance(ShadeQueue& q, const PixelAttributes& a) {
        std::copy_n(a.transmit[0], q.count, q.transmitRed);
        std::copy_n(a.transmit[1], q.count, q.transmitGreen);
        std::copy_n(a.transmit[2], q.count, q.transmitBlue);
    }

    // KHR_materials_sheen: the material so far (lights, ambient, environment; emission comes
    // after) dimmed by s = clamp(1 - max(c) E(n.v, r), 0, 1), plus the sheen's own light: per
    // light E n.l pi D V c (raster/sheen_lobe.h), ambient x occlusion x c E(n.v, r), and the
    // environment's irradiance x occlusion x c E(n.v, r) — a broad lobe lit by the irradiance,
    // where a GPU viewer reads a map prefiltered with the Charlie lobe (docs/formats.md). c the
    // sheen colour, r its roughness, each a factor times its texture.
    [[gnu::noinline]] void sheen(const ShadeQueue& q, PixelAttributes& a, const float* occlusion, const SurfaceAtPixels& m,
                                 StageCounters& counters) const {
        const int count = q.count;
        FetchedTexels color, roughnessTexels;
        fetchOrOnes(s_.textures.sheenColor, count, a, color, counters);
        fetchOrOnes(s_.textures.sheenRoughness, count, a, roughnessTexels, counters);
        float sheenColor[3][N], alpha[N], radiance[3][N];
        for (int i = 0; i < count; ++i) {
            const glm::vec3 c = glm::clamp(s_.brdf.sheenColor * glm::vec3(color.r[i], color.g[i], color.b[i]), 0.0f, 1.0f);
            const float r = std::max(kSheenRoughnessFloor, std::clamp(s_.brdf.sheenRoughness * roughnessTexels.a[i], 0.0f, 1.0f));
            alpha[i] = r * r;
            const float albedo = sheenAlbedo(sheenAlbedo_, m.nDotV[i], r);
            const float scale = std::clamp(1.0f - std::max({c.r, c.g, c.b}) * albedo, 0.0f, 1.0f);
            glm::vec3 ambient = s_.lighting.ambient;
            if (environment_) ambient += glm::vec3(m.irradiance[0][i], m.irradiance[1][i], m.irradiance[2][i]);
            for (int k = 0; k < 3; ++k) {
                sheenColor[k][i] = c[k];
                a.radiance[k][i] *= scale;
                if (transmissive_) a.transmit[k][i] *= scale;
                radiance[k][i] = ambient[k] * occlusion[i] * c[k] * albedo;
            }
        }
        for (int l = 0; l < s_.lighting.lightCount; ++l) {
            const Light& light = s_.lighting.lights[l];
            addSheenLight(light, q, a, m, sheenColor, alpha, radiance);
        }
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < count; ++i) a.radiance[k][i] += radiance[k][i];
        counters.sheenPixels += uint64_t(count);
    }

    // One light's sheen term E n.l pi D V c where n.l > 0. Not x light.specular: the sheen reads
    // the environment through its irradiance, which leaves out the dominant light drawn apart.
    // One function for every light type: a pow per pixel keeps this loop scalar anyway, so the
    // per-type copies addLight needs in order to vectorise would buy nothing here.
    void addSheenLight(const Light& light, const ShadeQueue& q, const PixelAttributes& a, const SurfaceAtPixels& m,
                       const float (&sheenColor)[3][N], const float* alpha, float (&radiance)[3][N]) const {
        float shadowed[N];
        shadowMask(light, q, shadowed);
        for (int i = 0; i < q.count; ++i) {
            Incident in = incident(light, a, i);
            in.intensity *= shadowed[i];
            const glm::vec3 n(a.normal[0][i], a.normal[1][i], a.normal[2][i]), view(m.view[0][i], m.view[1][i], m.view[2][i]);
            const float nDotL = glm::dot(n, in.toLight);
            const float nDotH = glm::dot(n, safeNormalize(in.toLight + view));
            const float lobe = float(M_PI) * charlieDistribution(alpha[i], nDotH) * neubeltVisibility(std::max(nDotL, 1e-4f), m.nDotV[i]);
            const bool lit = nDotL > 0.0f;
            for (int k = 0; k < 3; ++k) radiance[k][i] += lit ? in.intensity[k] * nDotL * lobe * sheenColor[k][i] : 0.0f;
        }
    }

    // KHR_materials_clearcoat: the coat's weight w = clearcoat x (0.04 + 0.96 (1 - n_c.v)^5)
    // and its radiance — ambient x occlusion x w (the layer's own albedo taken as 1, as the base's
    // ambient takes c_diff + F0), and per light E n_c.l pi D V w with the coat's roughness — for
    // underTheCoat to lay over the material once its emission is in.
    // Out of line, as underTheCoat: inlined into the shade queue, the coat's code kept GCC 12 from
    // if-converting the material and light loops of every metallic-roughness draw, coated or not
    // (-fopt-info-vec: "control flow in loop"), so they ran a pixel at a time.
    [[gnu::noinline]] void clearcoat(const ShadeQueue& q, PixelAttributes& a, const float* occlusion, const SurfaceAtPixels& m,
                   StageCounters& counters) const {
        const int count = q.count;
        FetchedTexels weight, roughness;
        fetchOrOnes(s_.textures.clearcoat, count, a, weight, counters);
        fetchOrOnes(s_.textures.clearcoatRoughness, count, a, roughness, counters);
        const float(&nc)[3][N] = layout_.tangent >= 0 ? a.coatNormal : a.normal;
        float alpha2[N], ncDotV[N];
        for (int i = 0; i < count; ++i) {
            const float r = std::max(0.03f, std::clamp(s_.brdf.clearcoatRoughness * roughness.g[i], 0.0f, 1.0f));
            alpha2[i] = r * r * r * r;
            const glm::vec3 n(nc[0][i], nc[1][i], nc[2][i]), view(m.view[0][i], m.view[1][i], m.view[2][i]);
            ncDotV[i] = std::max(glm::dot(n, view), 1e-4f);
            const float coat = std::clamp(s_.brdf.clearcoat * weight.r[i], 0.0f, 1.0f);
            a.coatWeight[i] = coat * (0.04f + 0.96f * pow5(1.0f - ncDotV[i]));
            for (int k = 0; k < 3; ++k) a.coatRadiance[k][i] = s_.lighting.ambient[k] * occlusion[i] * a.coatWeight[i];
        }
        // The environment seen in the coat: its filtered radiance around the coat's mirror
        // direction, times w, as the ambient term above takes the layer's albedo as 1.
        if (environment_)
            for (int i = 0; i < count; ++i) {
                const float r = std::max(0.03f, std::clamp(s_.brdf.clearcoatRoughness * roughness.g[i], 0.0f, 1.0f));
                float rgb[3];
                reflectedRadiance(nc[0][i], nc[1][i], nc[2][i], m.view[0][i], m.view[1][i], m.view[2][i], r, rgb);
                for (int k = 0; k < 3; ++k) a.coatRadiance[k][i] += rgb[k] * occlusion[i] * a.coatWeight[i];
            }
        for (int l = 0; l < s_.lighting.lightCount; ++l) {
            const Light& light = s_.lighting.lights[l];
            light.type == LightType::Directional ? addCoatLight<true>(light, q, a, m, nc, alpha2, ncDotV)
                                                 : addCoatLight<false>(light, q, a, m, nc, alpha2, ncDotV);
        }
        counters.clearcoatPixels += uint64_t(count);
    }

    // One light's coat term E n_c.l pi D V w at every pixel, where n_c.l > 0 (as addLight, whose
    // first lines it repeats: through a shared helper returning the Incident, GCC kept the struct
    // in memory and addLight's loop stopped vectorising).
    template <bool kDirectional>
    void addCoatLight(const Light& light, const ShadeQueue& q, PixelAttributes& a, const SurfaceAtPixels& m,
                      const float (&nc)[3][N], const float* alpha2, const float* ncDotV) const {
        float shadowed[N];
        shadowMask(light, q, shadowed);
        for (int i = 0; i < q.count; ++i) {
            Incident in;
            if constexpr (kDirectional)
                in = {-light.direction, light.intensity};
            else
                in = incident(light, a, i);
            in.intensity *= shadowed[i];
            const glm::vec3 n(nc[0][i], nc[1][i], nc[2][i]), view(m.view[0][i], m.view[1][i], m.view[2][i]);
            const float nDotL = glm::dot(n, in.toLight);
            const glm::vec3 h = safeNormalize(in.toLight + view);
            const float nDotH = std::max(glm::dot(n, h), 0.0f);
            const glm::vec3 term =
                in.intensity * (nDotL * specularLobe(alpha2[i], n, h, nDotH, nDotL, ncDotV[i]) * light.specular * a.coatWeight[i]);
            const bool lit = nDotL > 0.0f;  // a select, as in addLight
            a.coatRadiance[0][i] += lit ? term.r : 0.0f;
            a.coatRadiance[1][i] += lit ? term.g : 0.0f;
            a.coatRadiance[2][i] += lit ? term.b : 0.0f;
        }
    }

    // The coated material: the material, emission included, times 1 - w, plus the coat.
    // Under a coat, the light passed through (transmissive draws) is dimmed by the coat's weight
    // as the material is.
    [[gnu::noinline]] static void underTheCoat(int count, PixelAttributes& a, bool transmissive) {
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < count; ++i) a.radiance[k][i] = a.radiance[k][i] * (1.0f - a.coatWeight[i]) + a.coatRadiance[k][i];
        if (transmissive)
            for (int k = 0; k < 3; ++k)
                for (int i = 0; i < count; ++i) a.transmit[k][i] *= 1.0f - a.coatWeight[i];
    }

    // The BRDF's inputs from metallic and roughness (glTF 2.0 appendix B), with the view and the
    // ambient term, per pixel.
    void metallicRoughnessMaterial(int count, PixelAttributes& a, const float* occlusion, const FetchedTexels& texels,
                                   SurfaceAtPixels& m) const {
        for (int i = 0; i < count; ++i) {
            float metallic = s_.metallic * texels.b[i], roughness = s_.roughness * texels.g[i];
            metallic = std::clamp(metallic, 0.0f, 1.0f);
            // A floor on roughness: a perfect mirror's highlight is a delta no sample can hit.
            const float r = std::max(0.03f, std::clamp(roughness, 0.0f, 1.0f));
            m.alpha2[i] = r * r * r * r;  // (roughness²)²
            m.roughness[i] = r;
            const glm::vec3 albedo(a.albedo[0][i], a.albedo[1][i], a.albedo[2][i]);
            storeMaterial(i, albedo * (1.0f - metallic), glm::mix(glm::vec3(s_.dielectricF0), albedo, metallic), a, occlusion, m);
        }
    }

    // KHR_materials_specular: the dielectric part's F0 coloured and scaled, its F90 scaled,
    // min(dielectricF0 x specularColor, 1) x strength and strength, each mixed towards the metal's
    // (albedo and 1) by metallic. The metallic-roughness pass otherwise.
    void dielectricSpecularMaterial(int count, PixelAttributes& a, const float* occlusion, const FetchedTexels& texels,
                                    SurfaceAtPixels& m, StageCounters& counters) const {
        FetchedTexels strength, color;
        fetchOrOnes(s_.textures.specular, count, a, strength, counters);
        fetchOrOnes(s_.textures.specularColor, count, a, color, counters);
        for (int i = 0; i < count; ++i) {
            const float metallic = std::clamp(s_.metallic * texels.b[i], 0.0f, 1.0f);
            const float r = std::max(0.03f, std::clamp(s_.roughness * texels.g[i], 0.0f, 1.0f));
            m.alpha2[i] = r * r * r * r;
            m.roughness[i] = r;
            const float specular = std::clamp(s_.brdf.specularStrength * strength.a[i], 0.0f, 1.0f);
            const glm::vec3 tint = s_.brdf.specularColor * glm::vec3(color.r[i], color.g[i], color.b[i]);
            const glm::vec3 dielectricF0 = glm::min(s_.dielectricF0 * tint, glm::vec3(1.0f)) * specular;
            const glm::vec3 albedo(a.albedo[0][i], a.albedo[1][i], a.albedo[2][i]);
            storeMaterial(i, albedo * (1.0f - metallic), glm::mix(dielectricF0, albedo, metallic), a, occlusion, m);
            m.f90[i] = specular + (1.0f - specular) * metallic;
        }
    }

    // A slot's texels where it is bound (counted), else ones: the factors alone.
    void fetchOrOnes(const TextureBinding& slot, int count, PixelAttributes& a, FetchedTexels& out, StageCounters& counters) const {
        if (layout_.texCoord >= 0 && slot) {
            fetchAll(slot, a, count, out);
            counters.textureSamples += uint64_t(count);
            return;
        }
        for (float* channel : {out.r, out.g, out.b, out.a}) std::fill_n(channel, count, 1.0f);
    }

    // The same inputs from the specular-glossiness model (KHR_materials_pbrSpecularGlossiness):
    // c_diff = diffuse (1 - max(specular.rgb)), F0 = specular, alpha = (1 - glossiness)², with the
    // roughness floor of the metallic-roughness pass on 1 - glossiness. The albedo is the diffuse
    // colour (the base colour slot holds the diffuse texture).
    void specularGlossinessMaterial(int count, PixelAttributes& a, const float* occlusion, const FetchedTexels& texels,
                                    SurfaceAtPixels& m) const {
        for (int i = 0; i < count; ++i) {
            const glm::vec3 specular = glm::clamp(s_.brdf.specularFactor * glm::vec3(texels.r[i], texels.g[i], texels.b[i]), 0.0f, 1.0f);
            const float glossiness = std::clamp(s_.brdf.glossiness * texels.a[i], 0.0f, 1.0f);
            const float r = std::max(0.03f, 1.0f - glossiness);
            m.alpha2[i] = r * r * r * r;  // ((1 - glossiness)²)²
            m.roughness[i] = r;
            const glm::vec3 albedo(a.albedo[0][i], a.albedo[1][i], a.albedo[2][i]);
            storeMaterial(i, albedo * (1.0f - std::max({specular.r, specular.g, specular.b})), specular, a, occlusion, m);
        }
    }

    // Pixel i's BRDF inputs, its view vector, and the ambient term ambient x occlusion x (c_diff + F0).
    void storeMaterial(int i, const glm::vec3& diffuse, const glm::vec3& f0, PixelAttributes& a, const float* occlusion,
                       SurfaceAtPixels& m) const {
        const glm::vec3 n(a.normal[0][i], a.normal[1][i], a.normal[2][i]);
        const glm::vec3 p(a.position[0][i], a.position[1][i], a.position[2][i]);
        const glm::vec3 view = safeNormalize(s_.cameraPosition - p);
        m.nDotV[i] = std::max(glm::dot(n, view), 1e-4f);
        const glm::vec3 color = s_.lighting.ambient * occlusion[i] * (diffuse + f0);
        m.diffuse[0][i] = diffuse.x, m.diffuse[1][i] = diffuse.y, m.diffuse[2][i] = diffuse.z;
        m.f0[0][i] = f0.x, m.f0[1][i] = f0.y, m.f0[2][i] = f0.z;
        m.view[0][i] = view.x, m.view[1][i] = view.y, m.view[2][i] = view.z;
        a.radiance[0][i] = color.r, a.radiance[1][i] = color.g, a.radiance[2][i] = color.b;
    }

    // One light's term at every pixel: E n.l ((1 - F) c_diff + pi F D V), where n.l > 0, with
    // Schlick's F = F0 + (F90 - F0)(1 - v.h)^5, F90 = 1 unless kF90 (KHR_materials_specular).
    template <bool kDirectional, bool kF90>
    void addLight(const Light& light, const ShadeQueue& q, PixelAttributes& a, const SurfaceAtPixels& m) const {
        float shadowed[N];
        shadowMask(light, q, shadowed);
        for (int i = 0; i < q.count; ++i) {
            Incident in;
            if constexpr (kDirectional)
                in = {-light.direction, light.intensity};
            else
                in = incident(light, a, i);
            in.intensity *= shadowed[i];
            const glm::vec3 n(a.normal[0][i], a.normal[1][i], a.normal[2][i]);
            const glm::vec3 view(m.view[0][i], m.view[1][i], m.view[2][i]);
            const glm::vec3 f0(m.f0[0][i], m.f0[1][i], m.f0[2][i]);
            const glm::vec3 diffuse(m.diffuse[0][i], m.diffuse[1][i], m.diffuse[2][i]);
            const float alpha2 = m.alpha2[i], nDotV = m.nDotV[i];
            const float nDotL = glm::dot(n, in.toLight);
            const glm::vec3 h = safeNormalize(in.toLight + view);
            const float nDotH = std::max(glm::dot(n, h), 0.0f), vDotH = std::max(glm::dot(view, h), 0.0f);
            const float schlick = pow5(1.0f - vDotH);
            const glm::vec3 f90(kF90 ? m.f90[i] : 1.0f);
            const glm::vec3 fresnel = f0 + (f90 - f0) * schlick;
            // x light.specular: x 1 exactly for every light but an environment's dominant one.
            const glm::vec3 brdf =
                (glm::vec3(1.0f) - fresnel) * diffuse + specularLobe(alpha2, n, h, nDotH, nDotL, nDotV) * light.specular * fresnel;
            const glm::vec3 term = in.intensity * nDotL * brdf;
            // A select, not a branch: an unlit pixel's term may be Inf or NaN, and is not added.
            const bool lit = nDotL > 0.0f;
            a.radiance[0][i] += lit ? term.r : 0.0f;
            a.radiance[1][i] += lit ? term.g : 0.0f;
            a.radiance[2][i] += lit ? term.b : 0.0f;
        }
    }

    // The environment's light at every pixel (raster/environment_light.h): occlusion x (c_diff E(n)
    // + S(r, roughness) (F0 A + F90 B)), r the view reflected about n, F90 = 1 unless kF90.
    template <bool kF90>
    void addEnvironment(int count, PixelAttributes& a, const float* occlusion, SurfaceAtPixels& m) const {
        // Two passes, as the material's: the reflections' fetches (a loop GCC vectorises with
        // gathers), then the irradiance, the split-sum table and the sum per pixel.
        float specular[3][N];
        for (int i = 0; i < count; ++i) {
            const float nx = a.normal[0][i], ny = a.normal[1][i], nz = a.normal[2][i];
            const float twoNDotV = 2.0f * (nx * m.view[0][i] + ny * m.view[1][i] + nz * m.view[2][i]);
            environment_->specularAt(twoNDotV * nx - m.view[0][i], twoNDotV * ny - m.view[1][i], twoNDotV * nz - m.view[2][i],
                                     m.roughness[i], specular[0][i], specular[1][i], specular[2][i]);
        }
        const float* dfg = EnvironmentLight::dfgTable();
        for (int i = 0; i < count; ++i) {
            float scaleA, scaleB;
            EnvironmentLight::dfgAt(dfg, m.nDotV[i], m.roughness[i], scaleA, scaleB);
            const glm::vec3 e = glm::max(
                EnvironmentLight::irradianceAt(*environmentSh_, a.normal[0][i], a.normal[1][i], a.normal[2][i]), glm::vec3(0.0f));
            m.irradiance[0][i] = e.x, m.irradiance[1][i] = e.y, m.irradiance[2][i] = e.z;
            const float f90 = kF90 ? m.f90[i] : 1.0f;
            a.radiance[0][i] += occlusion[i] * (m.diffuse[0][i] * e.x + specular[0][i] * (m.f0[0][i] * scaleA + f90 * scaleB));
            a.radiance[1][i] += occlusion[i] * (m.diffuse[1][i] * e.y + specular[1][i] * (m.f0[1][i] * scaleA + f90 * scaleB));
            a.radiance[2][i] += occlusion[i] * (m.diffuse[2][i] * e.z + specular[2][i] * (m.f0[2][i] * scaleA + f90 * scaleB));
        }
    }

    // Lambert's share of the environment: occlusion x E(n), added to each pixel's irradiance.
    void environmentIrradiance(int count, const PixelAttributes& a, const float* occlusion, float (&irradiance)[3][N]) const {
        for (int i = 0; i < count; ++i) {
            const glm::vec3 e = glm::max(
                EnvironmentLight::irradianceAt(*environmentSh_, a.normal[0][i], a.normal[1][i], a.normal[2][i]),
                glm::vec3(0.0f));
            for (int k = 0; k < 3; ++k) irradiance[k][i] += occlusion[i] * e[k];
        }
    }

    // S(r, roughness) for the view (vx, vy, vz) reflected about the normal (nx, ny, nz).
    [[gnu::always_inline]] void reflectedRadiance(float nx, float ny, float nz, float vx, float vy, float vz, float roughness,
                                                  float (&rgb)[3]) const {
        const float twoNDotV = 2.0f * (nx * vx + ny * vy + nz * vz);
        environment_->specularAt(twoNDotV * nx - vx, twoNDotV * ny - vy, twoNDotV * nz - vz, roughness, rgb[0], rgb[1], rgb[2]);
    }

    void addEmissive(int count, PixelAttributes& a, StageCounters& counters) const {
        const glm::vec3 e = s_.emissive;
        if (layout_.texCoord >= 0 && s_.textures.emissive) {
            FetchedTexels texels;
            fetchAll(s_.textures.emissive, a, count, texels);
            const float* channel[3] = {texels.r, texels.g, texels.b};
            for (int k = 0; k < 3; ++k)
                for (int i = 0; i < count; ++i) a.radiance[k][i] += e[k] * channel[k][i];
            counters.textureSamples += uint64_t(count);
            return;
        }
        for (int k = 0; k < 3; ++k)
            for (int i = 0; i < count; ++i) a.radiance[k][i] += e[k];
    }

    static void writeOut(ShadeQueue& q, const float (*rgb)[N], const float (*alpha)[N]) {
        for (int i = 0; i < q.count; ++i) {
            q.red[i] = rgb[0][i], q.green[i] = rgb[1][i], q.blue[i] = rgb[2][i];
            q.alpha[i] = alpha[0][i];
        }
    }

    /// pi D V: the GGX distribution and the height-correlated Smith visibility, without Fresnel.
    static float specularLobe(float alpha2, const glm::vec3& n, const glm::vec3& h, float nDotH, float nDotL, float nDotV) {
        // n.h² (a² - 1) + 1 written as a² n.h² + |n x h|²: near the highlight's peak,
        // 1 - n.h² cancels in float, the cross product does not (Filament's form).
        const glm::vec3 nCrossH = glm::cross(n, h);
        const float dDenominator = alpha2 * nDotH * nDotH + glm::dot(nCrossH, nCrossH);
        const float distribution = alpha2 / (float(M_PI) * dDenominator * dDenominator);
        const float visibility = 0.5f / (nDotL * std::sqrt(nDotV * nDotV * (1.0f - alpha2) + alpha2) +
                                         nDotV * std::sqrt(nDotL * nDotL * (1.0f - alpha2) + alpha2));
        return float(M_PI) * distribution * visibility;
    }

    /// x^5 by three multiplications, the same bits in every lane and on every instruction set
    /// (std::pow is a library call per pixel, a tenth of a textured frame).
    static float pow5(float x) {
        const float x2 = x * x;
        return x2 * x2 * x;
    }

    static glm::vec3 safeNormalize(const glm::vec3& x) {
        const float len2 = glm::dot(x, x);
        const glm::vec3 unit = x / std::sqrt(len2);  // selected, not branched to: loops stay vectorisable
        return len2 > 0.0f ? unit : glm::vec3(0.0f, 0.0f, 1.0f);
    }

    const DrawState& s_;
    VaryingLayout layout_;
    bool hasEmissive_ = false;
    bool coated_ = false;  // KHR_materials_clearcoat
    bool mapsNormals_ = false;  // a normal map perturbs the normal or the coat's (needs tangents)
    const float* sheenAlbedo_ = nullptr;  // KHR_materials_sheen: its albedo table, when the draw has a sheen
    bool transmissive_ = false;           // KHR_materials_transmission
    bool volume_ = false;                 // KHR_materials_volume: an attenuating thickness
    float logAttenuation_[3] = {}, attenuation_[3] = {1.0f, 1.0f, 1.0f};
    const EnvironmentLight* environment_ = nullptr;
    const glm::vec3 (*environmentSh_)[9] = nullptr;  // its irradiance, less a dominant light drawn apart
    bool fusedLambert_ = false;
};

/// The InterpolatedQueue of a shader that has one (raster/shade.h), else an empty stand-in.
template <class Shader, bool = Shader::kInterpolatesAcrossTriangles>
struct InterpolatedQueueOf {
    struct type {};
};
template <class Shader>
struct InterpolatedQueueOf<Shader, true> {
    using type = typename Shader::InterpolatedQueue;
};
template <class Shader>
using InterpolatedQueueFor = typename InterpolatedQueueOf<Shader>::type;

}  // namespace cuberille::raster
