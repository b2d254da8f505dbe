#include "bench/llvmpipe_peer.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <cstdio>
#include <stdexcept>
#include <string>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

namespace cuberille::bench {
namespace {

// GL 2.0+ entry points are not exported by libOSMesa: fetch them once.
#define CUB_GL_FUNCTIONS(X)                                                                   \
    X(PFNGLCREATESHADERPROC, glCreateShader)                                                  \
    X(PFNGLSHADERSOURCEPROC, glShaderSource)                                                  \
    X(PFNGLCOMPILESHADERPROC, glCompileShader)                                                \
    X(PFNGLGETSHADERIVPROC, glGetShaderiv)                                                    \
    X(PFNGLGETSHADERINFOLOGPROC, glGetShaderInfoLog)                                          \
    X(PFNGLCREATEPROGRAMPROC, glCreateProgram)                                                \
    X(PFNGLATTACHSHADERPROC, glAttachShader)                                                  \
    X(PFNGLBINDATTRIBLOCATIONPROC, glBindAttribLocation)                                      \
    X(PFNGLLINKPROGRAMPROC, glLinkProgram)                                                    \
    X(PFNGLUSEPROGRAMPROC, glUseProgram)                                                      \
    X(PFNGLGETUNIFORMLOCATIONPROC, glGetUniformLocation)                                      \
    X(PFNGLUNIFORMMATRIX4FVPROC, glUniformMatrix4fv)                                          \
    X(PFNGLUNIFORM3FVPROC, glUniform3fv)                                                      \
    X(PFNGLUNIFORM4FVPROC, glUniform4fv)                                                      \
    X(PFNGLUNIFORM1IPROC, glUniform1i)                                                        \
    X(PFNGLUNIFORM1IVPROC, glUniform1iv)                                                      \
    X(PFNGLUNIFORM1FPROC, glUniform1f)                                                        \
    X(PFNGLUNIFORM1FVPROC, glUniform1fv)                                                      \
    X(PFNGLACTIVETEXTUREPROC, glActiveTexture)                                                \
    X(PFNGLDISABLEVERTEXATTRIBARRAYPROC, glDisableVertexAttribArray)                          \
    X(PFNGLGENBUFFERSPROC, glGenBuffers)                                                      \
    X(PFNGLBINDBUFFERPROC, glBindBuffer)                                                      \
    X(PFNGLBUFFERDATAPROC, glBufferData)                                                      \
    X(PFNGLENABLEVERTEXATTRIBARRAYPROC, glEnableVertexAttribArray)                            \
    X(PFNGLVERTEXATTRIBPOINTERPROC, glVertexAttribPointer)                                    \
    X(PFNGLGENFRAMEBUFFERSPROC, glGenFramebuffers)                                            \
    X(PFNGLBINDFRAMEBUFFERPROC, glBindFramebuffer)                                            \
    X(PFNGLGENRENDERBUFFERSPROC, glGenRenderbuffers)                                          \
    X(PFNGLBINDRENDERBUFFERPROC, glBindRenderbuffer)                                          \
    X(PFNGLRENDERBUFFERSTORAGEMULTISAMPLEPROC, glRenderbufferStorageMultisample)              \
    X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, glFramebufferRenderbuffer)                            \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, glCheckFramebufferStatus)                              \
    X(PFNGLBLITFRAMEBUFFERPROC, glBlitFramebuffer)

#define CUB_DECLARE(type, name) type p_##name = nullptr;
CUB_GL_FUNCTIONS(CUB_DECLARE)

// The shaders are raster/shade.h written in GLSL 1.20, so the peer does the work Cuberille does:
// the same varyings, Lambert or glTF's metallic-roughness BRDF (GGX, height-correlated Smith,
// Schlick) over every light of the scene, base-colour, metallic-roughness, normal, occlusion and
// emissive textures sampled with the same filters from the same texels (Cuberille's own mip
// chain, uploaded level by level in its texel format), alpha masks and double-sided normals. One
// program per combination of features, compiled once, as an engine's shader variants are; the
// bench scenes' one directional light has its own variant without the light loop, as Cuberille
// has its fused Lambert loop. Not mirrored: KHR_texture_transform's UV transform, blending's
// back-to-front sort of meshes (docs/performance.md says where this matters), and the material
// extensions' inputs (KHR_materials_ior's F0, KHR_materials_pbrSpecularGlossiness, KHR_materials_specular, KHR_materials_clearcoat), which no
// bench scene uses.
const char* kVertexShader = R"(
attribute vec3 position; attribute vec3 normal; attribute vec3 color; attribute vec2 uv; attribute vec4 tangent;
uniform mat4 clipFromWorld;
varying vec3 vNormal, vPosition, vColor; varying vec2 vUV; varying vec4 vTangent;
void main() {
  vNormal = normal;
#ifdef WORLD_POSITION
  vPosition = position;
#endif
#ifdef VERTEX_COLOR
  vColor = color;
#endif
#ifdef TEXTURED
  vUV = uv;
#endif
#ifdef NORMAL_TEX
  vTangent = tangent;
#endif
  gl_Position = clipFromWorld * vec4(position, 1.0);
})";

const char* kFragmentShader = R"(
uniform vec4 baseColor; uniform float metallicFactor, roughnessFactor, normalScale, occlusionStrength, alphaCutoff;
uniform vec3 emissiveFactor, cameraPosition, ambient;
uniform int lightCount; uniform int lightType[8];
uniform vec3 lightPosition[8], lightDirection[8], lightIntensity[8];
uniform float lightRange[8], lightCosInner[8], lightCosOuter[8];
uniform sampler2D baseColorTex, metallicRoughnessTex, normalTex, occlusionTex, emissiveTex;
varying vec3 vNormal, vPosition, vColor; varying vec2 vUV; varying vec4 vTangent;

vec3 safeNormalize(vec3 x) { float l2 = dot(x, x); return l2 > 0.0 ? x / sqrt(l2) : vec3(0.0, 0.0, 1.0); }

// Direction to light i and the intensity arriving (shade.h, incident()).
void incident(int i, vec3 p, out vec3 l, out vec3 e) {
  if (lightType[i] == 0) { l = -lightDirection[i]; e = lightIntensity[i]; return; }
  vec3 d = lightPosition[i] - p;
  float distance2 = max(dot(d, d), 1e-12);
  l = d / sqrt(distance2);
  float attenuation = 1.0 / distance2;
  if (lightRange[i] > 0.0) {
    float r = distance2 / (lightRange[i] * lightRange[i]);
    float window = clamp(1.0 - r * r, 0.0, 1.0);
    attenuation *= window * window;
  }
  if (lightType[i] == 2) {
    float scale = 1.0 / max(0.001, lightCosInner[i] - lightCosOuter[i]);
    float cone = clamp((dot(lightDirection[i], -l) - lightCosOuter[i]) * scale, 0.0, 1.0);
    attenuation *= cone * cone;
  }
  e = lightIntensity[i] * attenuation;
}

void main() {
  vec4 albedo = baseColor;
#ifdef VERTEX_COLOR
  albedo.rgb *= vColor;
#endif
#ifdef BASE_TEX
  albedo *= texture2D(baseColorTex, vUV);
#endif
#ifdef MASK
  if (!(albedo.a >= alphaCutoff)) discard;
  albedo.a = 1.0;
#endif
#ifdef UNLIT
  gl_FragColor = albedo;
#else
  vec3 n = vNormal;
#ifdef NORMAL_TEX
  vec3 nrm = safeNormalize(n);
  vec3 t = safeNormalize(vTangent.xyz - nrm * dot(nrm, vTangent.xyz));
  vec3 b = cross(nrm, t) * (vTangent.w < 0.0 ? -1.0 : 1.0);
  vec3 texel = texture2D(normalTex, vUV).rgb;
  vec3 m = vec3(normalScale * (2.0 * texel.r - 1.0), normalScale * (2.0 * texel.g - 1.0), 2.0 * texel.b - 1.0);
  n = t * m.x + b * m.y + nrm * m.z;
#endif
  float len2 = dot(n, n);
  n = len2 > 0.0 ? n * ((gl_FrontFacing ? 1.0 : -1.0) / sqrt(len2)) : vec3(0.0);
  float occlusion = 1.0;
#ifdef OCCLUSION_TEX
  occlusion = 1.0 + occlusionStrength * (texture2D(occlusionTex, vUV).r - 1.0);
#endif
  vec3 color;
#if defined(METALLIC_ROUGHNESS)
  float metallic = metallicFactor, roughness = roughnessFactor;
#ifdef METALLIC_ROUGHNESS_TEX
  vec4 mr = texture2D(metallicRoughnessTex, vUV);
  metallic *= mr.b; roughness *= mr.g;
#endif
  metallic = clamp(metallic, 0.0, 1.0);
  float r = max(0.03, clamp(roughness, 0.0, 1.0));
  float alpha2 = r * r * r * r;
  vec3 diffuse = albedo.rgb * (1.0 - metallic);
  vec3 f0 = mix(vec3(0.04), albedo.rgb, metallic);
  vec3 view = safeNormalize(cameraPosition - vPosition);
  float nDotV = max(dot(n, view), 1e-4);
  color = ambient * occlusion * (diffuse + f0);
  for (int i = 0; i < lightCount; ++i) {
    vec3 l, e;
    incident(i, vPosition, l, e);
    float nDotL = dot(n, l);
    if (!(nDotL > 0.0)) continue;
    vec3 h = safeNormalize(l + view);
    float nDotH = max(dot(n, h), 0.0), vDotH = max(dot(view, h), 0.0);
    float schlick = pow(1.0 - vDotH, 5.0);
    vec3 fresnel = f0 + (vec3(1.0) - f0) * schlick;
    vec3 nCrossH = cross(n, h);
    float dDenominator = alpha2 * nDotH * nDotH + dot(nCrossH, nCrossH);
    float distribution = alpha2 / (3.14159265 * dDenominator * dDenominator);
    float visibility = 0.5 / (nDotL * sqrt(nDotV * nDotV * (1.0 - alpha2) + alpha2) +
                              nDotV * sqrt(nDotL * nDotL * (1.0 - alpha2) + alpha2));
    vec3 brdf = (vec3(1.0) - fresnel) * diffuse + 3.14159265 * distribution * visibility * fresnel;
    color += e * nDotL * brdf;
  }
#elif defined(ONE_DIRECTIONAL_LIGHT)
  color = albedo.rgb * (ambient * occlusion + lightIntensity[0] * max(0.0, dot(n, -lightDirection[0])));
#else
  vec3 irradiance = ambient * occlusion;
  for (int i = 0; i < lightCount; ++i) {
    vec3 l, e;
    incident(i, vPosition, l, e);
    irradiance += e * max(0.0, dot(n, l));
  }
  color = albedo.rgb * irradiance;
#endif
#ifdef EMISSIVE
  vec3 emissive = emissiveFactor;
#ifdef EMISSIVE_TEX
  emissive *= texture2D(emissiveTex, vUV).rgb;
#endif
  color += emissive;
#endif
  gl_FragColor = vec4(color, albedo.a);
#endif
})";

GLuint compile(GLenum type, const char* source) {
    GLuint s = p_glCreateShader(type);
    p_glShaderSource(s, 1, &source, nullptr);
    p_glCompileShader(s);
    GLint ok = 0;
    p_glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[1024];
        p_glGetShaderInfoLog(s, sizeof log, nullptr, log);
        throw std::runtime_error(std::string("llvmpipe shader: ") + log);
    }
    return s;
}

struct MeshBuffers {
    GLuint positions = 0, normals = 0, colors = 0, uvs = 0, tangents = 0, indices = 0;
    GLsizei indexCount = 0;
    size_t program = 0;  // into Impl::programs
};

/// One shader variant and its uniform locations.
struct Program {
    std::string defines;
    GLuint id = 0;
    GLint clipFromWorld, baseColor, metallic, roughness, normalScale, occlusionStrength, alphaCutoff, emissive,
        cameraPosition, ambient, lightCount, lightType, lightPosition, lightDirection, lightIntensity, lightRange,
        lightCosInner, lightCosOuter;
};

/// The mesh's texture slots in texture-unit order; kSamplerNames names their samplers alike.
std::array<const scene::MeshTexture*, 5> textureSlots(const scene::Mesh& m) {
    return {&m.textures.baseColor, &m.textures.metallicRoughness, &m.textures.normal, &m.textures.occlusion,
            &m.textures.emissive};
}
constexpr const char* kSamplerNames[] = {"baseColorTex", "metallicRoughnessTex", "normalTex", "occlusionTex", "emissiveTex"};

/// What a mesh's draw reads and computes: the shader variant's #defines and the buffers upload()
/// makes, from one place.
struct MeshFeatures {
    bool vertexColor, textured, normalTexture;
    std::string defines;
};

MeshFeatures featuresOf(const scene::Mesh& m, const raster::Lighting& lighting) {
    MeshFeatures f;
    f.vertexColor = m.colors.size() == m.positions.size() && !m.colors.empty();
    f.textured = m.texCoords.size() == m.positions.size() && !m.texCoords.empty();
    f.normalTexture = f.textured && bool(m.textures.normal) && m.tangents.size() == m.positions.size();
    auto define = [&](bool on, const char* name) {
        if (on) f.defines += std::string("#define ") + name + "\n";
    };
    bool onlyOneDirectional = lighting.lightCount == 1 && lighting.lights[0].type == raster::LightType::Directional;
    const bool mr = m.metallicRoughness && !m.unlit;
    bool pointOrSpot = false;
    for (int i = 0; i < lighting.lightCount; ++i) pointOrSpot = pointOrSpot || lighting.lights[i].type != raster::LightType::Directional;
    define(m.unlit, "UNLIT");
    define(mr, "METALLIC_ROUGHNESS");
    define(mr || pointOrSpot, "WORLD_POSITION");
    define(!mr && onlyOneDirectional, "ONE_DIRECTIONAL_LIGHT");
    define(f.vertexColor, "VERTEX_COLOR");
    define(f.textured, "TEXTURED");
    define(f.textured && bool(m.textures.baseColor), "BASE_TEX");
    define(f.textured && mr && bool(m.textures.metallicRoughness), "METALLIC_ROUGHNESS_TEX");
    define(f.normalTexture, "NORMAL_TEX");
    define(f.textured && bool(m.textures.occlusion), "OCCLUSION_TEX");
    define(m.emissive != glm::vec3(0.0f), "EMISSIVE");
    define(f.textured && bool(m.textures.emissive), "EMISSIVE_TEX");
    define(m.alphaMode == raster::AlphaMode::Mask, "MASK");
    return f;
}

GLint wrapOf(raster::WrapMode w) {
    switch (w) {
        case raster::WrapMode::Repeat: return GL_REPEAT;
        case raster::WrapMode::ClampToEdge: return GL_CLAMP_TO_EDGE;
        case raster::WrapMode::MirroredRepeat: return GL_MIRRORED_REPEAT;
    }
    return GL_REPEAT;
}

GLint minFilterOf(raster::MinFilter f) {
    switch (f) {
        case raster::MinFilter::Nearest: return GL_NEAREST;
        case raster::MinFilter::Linear: return GL_LINEAR;
        case raster::MinFilter::NearestMipmapNearest: return GL_NEAREST_MIPMAP_NEAREST;
        case raster::MinFilter::LinearMipmapNearest: return GL_LINEAR_MIPMAP_NEAREST;
        case raster::MinFilter::NearestMipmapLinear: return GL_NEAREST_MIPMAP_LINEAR;
        case raster::MinFilter::LinearMipmapLinear: return GL_LINEAR_MIPMAP_LINEAR;
    }
    return GL_LINEAR_MIPMAP_LINEAR;
}

/// The same view as Cuberille's clip-space draws, with OpenGL's [-1, 1] depth.
glm::mat4 glClipFromWorld(const scene::Scene& scene, int width, int height) {
    return glm::perspectiveRH_NO(glm::radians(scene.camera.verticalFovDegrees), float(width) / height,
                                 scene.camera.nearPlane, scene.camera.farPlane) *
           scene.camera.viewFromWorld();
}

/// Back faces culled as Scene::draw culls them: by the scene's mode, never on a double-sided mesh.
void setCulling(const scene::Scene& scene, const scene::Mesh& mesh) {
    if (mesh.doubleSided || scene.cull == raster::CullMode::None)
        glDisable(GL_CULL_FACE);
    else
        glEnable(GL_CULL_FACE);
}

}  // namespace

struct LlvmpipePeer::Impl {
    int width, height, msaa;
    GLuint depthProgram = 0;
    GLint depthClipFromWorld = -1;
    OSMesaContext context = nullptr;
    std::vector<unsigned char> buffer;
    GLuint fbo = 0;
    std::vector<Program> programs;
    std::vector<MeshBuffers> meshes;
    std::map<const raster::Texture*, GLuint> textures;

    size_t programFor(const std::string& defines);
    GLuint textureFor(const raster::Texture& t);
};

size_t LlvmpipePeer::Impl::programFor(const std::string& defines) {
    for (size_t i = 0; i < programs.size(); ++i)
        if (programs[i].defines == defines) return i;
    Program p;
    p.defines = defines;
    const std::string vertex = "#version 120\n" + defines + kVertexShader;
    const std::string fragment = "#version 120\n" + defines + kFragmentShader;
    p.id = p_glCreateProgram();
    p_glAttachShader(p.id, compile(GL_VERTEX_SHADER, vertex.c_str()));
    p_glAttachShader(p.id, compile(GL_FRAGMENT_SHADER, fragment.c_str()));
    const char* attributes[] = {"position", "normal", "color", "uv", "tangent"};
    for (GLuint i = 0; i < 5; ++i) p_glBindAttribLocation(p.id, i, attributes[i]);
    p_glLinkProgram(p.id);
    p_glUseProgram(p.id);
    auto at = [&](const char* name) { return p_glGetUniformLocation(p.id, name); };
    p.clipFromWorld = at("clipFromWorld"), p.baseColor = at("baseColor"), p.metallic = at("metallicFactor");
    p.roughness = at("roughnessFactor"), p.normalScale = at("normalScale"), p.occlusionStrength = at("occlusionStrength");
    p.alphaCutoff = at("alphaCutoff"), p.emissive = at("emissiveFactor"), p.cameraPosition = at("cameraPosition");
    p.ambient = at("ambient"), p.lightCount = at("lightCount"), p.lightType = at("lightType");
    p.lightPosition = at("lightPosition"), p.lightDirection = at("lightDirection"), p.lightIntensity = at("lightIntensity");
    p.lightRange = at("lightRange"), p.lightCosInner = at("lightCosInner"), p.lightCosOuter = at("lightCosOuter");
    for (int unit = 0; unit < 5; ++unit) p_glUniform1i(at(kSamplerNames[unit]), unit);
    programs.push_back(p);
    return programs.size() - 1;
}

// Cuberille's own mip chain, level by level, in its texel format: 8-bit texels as sRGB or UNORM
// bytes (the sampler decodes them, as Cuberille's table does), float texels as RGBA32F.
GLuint LlvmpipePeer::Impl::textureFor(const raster::Texture& t) {
    if (auto found = textures.find(&t); found != textures.end()) return found->second;
    GLuint id;
    glGenTextures(1, &id);
    glBindTexture(GL_TEXTURE_2D, id);
    for (int level = 0; level < t.levelCount(); ++level) {
        const int w = t.width(level), h = t.height(level);
        if (t.format() != raster::TexelFormat::LinearFloat) {
            const GLint format = t.format() == raster::TexelFormat::Srgb8 ? GL_SRGB8_ALPHA8 : GL_RGBA8;
            const std::vector<uint32_t> packed = t.packedRows(level);
            glTexImage2D(GL_TEXTURE_2D, level, format, w, h, 0, GL_RGBA, GL_UNSIGNED_BYTE, packed.data());
            continue;
        }
        std::vector<glm::vec4> texels(size_t(w) * h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) texels[size_t(y) * w + x] = t.texel(level, x, y);
        glTexImage2D(GL_TEXTURE_2D, level, GL_RGBA32F, w, h, 0, GL_RGBA, GL_FLOAT, texels.data());
    }
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, t.levelCount() - 1);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, minFilterOf(t.filter().minify));
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, t.filter().magnifyNearest ? GL_NEAREST : GL_LINEAR);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, wrapOf(t.wrapU()));
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, wrapOf(t.wrapV()));
    textures[&t] = id;
    return id;
}

bool LlvmpipePeer::available() { return true; }

const std::vector<unsigned char>& LlvmpipePeer::pixels() const { return impl_->buffer; }

LlvmpipePeer::LlvmpipePeer(int width, int height, int msaa) : impl_(std::make_unique<Impl>()) {
    Impl& m = *impl_;
    m.width = width, m.height = height, m.msaa = msaa;
    const int attribs[] = {OSMESA_FORMAT, OSMESA_RGBA, OSMESA_DEPTH_BITS, 24,
                           OSMESA_PROFILE, OSMESA_COMPAT_PROFILE, 0};
    m.context = OSMesaCreateContextAttribs(attribs, nullptr);
    if (!m.context) throw std::runtime_error("OSMesa: cannot create a context");
    m.buffer.resize(size_t(width) * height * 4);
    if (!OSMesaMakeCurrent(m.context, m.buffer.data(), GL_UNSIGNED_BYTE, width, height))
        throw std::runtime_error("OSMesa: cannot make the context current");
#define CUB_LOAD(type, name)                                                        \
    p_##name = reinterpret_cast<type>(OSMesaGetProcAddress(#name));                 \
    if (!p_##name) throw std::runtime_error("OSMesa: missing " #name);
    CUB_GL_FUNCTIONS(CUB_LOAD)

    if (msaa > 1) {
        GLuint color, depth;
        p_glGenFramebuffers(1, &m.fbo);
        p_glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
        p_glGenRenderbuffers(1, &color);
        p_glBindRenderbuffer(GL_RENDERBUFFER, color);
        p_glRenderbufferStorageMultisample(GL_RENDERBUFFER, msaa, GL_RGBA8, width, height);
        p_glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, color);
        p_glGenRenderbuffers(1, &depth);
        p_glBindRenderbuffer(GL_RENDERBUFFER, depth);
        p_glRenderbufferStorageMultisample(GL_RENDERBUFFER, msaa, GL_DEPTH_COMPONENT24, width, height);
        p_glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth);
        if (p_glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
            throw std::runtime_error("OSMesa: multisampled framebuffer incomplete");
    }
    glViewport(0, 0, width, height);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glEnable(GL_CULL_FACE);
    glCullFace(GL_BACK);
    glFrontFace(GL_CCW);
}

LlvmpipePeer::~LlvmpipePeer() {
    if (impl_->context) OSMesaDestroyContext(impl_->context);
}

void LlvmpipePeer::upload(const scene::Scene& scene) {
    auto buffer = [](GLenum target, const void* data, size_t bytes) {
        GLuint b = 0;
        if (bytes == 0) return b;
        p_glGenBuffers(1, &b);
        p_glBindBuffer(target, b);
        p_glBufferData(target, GLsizeiptr(bytes), data, GL_STATIC_DRAW);
        return b;
    };
    for (const scene::Mesh& mesh : scene.meshes) {
        MeshBuffers b;
        const MeshFeatures features = featuresOf(mesh, scene.lighting);
        b.program = impl_->programFor(features.defines);
        b.positions = buffer(GL_ARRAY_BUFFER, mesh.positions.data(), mesh.positions.size() * sizeof(glm::vec3));
        b.normals = buffer(GL_ARRAY_BUFFER, mesh.normals.data(), mesh.normals.size() * sizeof(glm::vec3));
        if (features.vertexColor)
            b.colors = buffer(GL_ARRAY_BUFFER, mesh.colors.data(), mesh.colors.size() * sizeof(glm::vec3));
        if (features.textured)
            b.uvs = buffer(GL_ARRAY_BUFFER, mesh.texCoords.data(), mesh.texCoords.size() * sizeof(glm::vec2));
        if (features.normalTexture)
            b.tangents = buffer(GL_ARRAY_BUFFER, mesh.tangents.data(), mesh.tangents.size() * sizeof(glm::vec4));
        b.indices = buffer(GL_ELEMENT_ARRAY_BUFFER, mesh.indices.data(), mesh.indices.size() * sizeof(uint32_t));
        b.indexCount = GLsizei(mesh.indices.size());
        for (const scene::MeshTexture* t : textureSlots(mesh))
            if (t->texture) impl_->textureFor(*t->texture);
        impl_->meshes.push_back(b);
    }
    glFinish();
}

double LlvmpipePeer::renderFrame(const scene::Scene& scene) {
    Impl& m = *impl_;
    const auto t0 = std::chrono::steady_clock::now();
    const glm::mat4 clipFromWorld = glClipFromWorld(scene, m.width, m.height);
    if (m.fbo) p_glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
    glClearColor(scene.background.r, scene.background.g, scene.background.b, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    const raster::Lighting& lighting = scene.lighting;
    GLint types[raster::kMaxLights];
    glm::vec3 positions[raster::kMaxLights], directions[raster::kMaxLights], intensities[raster::kMaxLights];
    float ranges[raster::kMaxLights], inner[raster::kMaxLights], outer[raster::kMaxLights];
    for (int i = 0; i < lighting.lightCount; ++i) {
        const raster::Light& l = lighting.lights[i];
        types[i] = GLint(l.type), positions[i] = l.position, directions[i] = l.direction, intensities[i] = l.intensity;
        ranges[i] = l.range, inner[i] = l.cosInnerCone, outer[i] = l.cosOuterCone;
    }
    // Opaque and masked meshes first, then blended ones without depth writes, as Scene::draw.
    std::vector<size_t> order, blended;
    for (size_t i = 0; i < m.meshes.size(); ++i)
        (scene.meshes[i].alphaMode == raster::AlphaMode::Blend ? blended : order).push_back(i);
    order.insert(order.end(), blended.begin(), blended.end());
    size_t bound = SIZE_MAX;
    for (size_t i : order) {
        const MeshBuffers& b = m.meshes[i];
        const scene::Mesh& mesh = scene.meshes[i];
        const Program& p = m.programs[b.program];
        if (b.program != bound) {
            p_glUseProgram(p.id);
            p_glUniformMatrix4fv(p.clipFromWorld, 1, GL_FALSE, glm::value_ptr(clipFromWorld));
            p_glUniform3fv(p.cameraPosition, 1, glm::value_ptr(scene.camera.position));
            p_glUniform3fv(p.ambient, 1, glm::value_ptr(lighting.ambient));
            p_glUniform1i(p.lightCount, lighting.lightCount);
            if (lighting.lightCount > 0) {
                p_glUniform1iv(p.lightType, lighting.lightCount, types);
                p_glUniform3fv(p.lightPosition, lighting.lightCount, glm::value_ptr(positions[0]));
                p_glUniform3fv(p.lightDirection, lighting.lightCount, glm::value_ptr(directions[0]));
                p_glUniform3fv(p.lightIntensity, lighting.lightCount, glm::value_ptr(intensities[0]));
                p_glUniform1fv(p.lightRange, lighting.lightCount, ranges);
                p_glUniform1fv(p.lightCosInner, lighting.lightCount, inner);
                p_glUniform1fv(p.lightCosOuter, lighting.lightCount, outer);
            }
            bound = b.program;
        }
        const glm::vec4 baseColor(mesh.color, mesh.alpha);
        p_glUniform4fv(p.baseColor, 1, glm::value_ptr(baseColor));
        p_glUniform1f(p.metallic, mesh.metallic);
        p_glUniform1f(p.roughness, mesh.roughness);
        p_glUniform1f(p.normalScale, mesh.normalScale);
        p_glUniform1f(p.occlusionStrength, mesh.occlusionStrength);
        p_glUniform1f(p.alphaCutoff, mesh.alphaCutoff);
        p_glUniform3fv(p.emissive, 1, glm::value_ptr(mesh.emissive));
        const auto slots = textureSlots(mesh);
        for (int unit = 0; unit < 5; ++unit) {
            if (!slots[unit]->texture) continue;
            p_glActiveTexture(GL_TEXTURE0 + unit);
            glBindTexture(GL_TEXTURE_2D, m.textures.at(slots[unit]->texture.get()));
        }
        setCulling(scene, mesh);
        const bool blend = mesh.alphaMode == raster::AlphaMode::Blend;
        if (blend) {
            glEnable(GL_BLEND);
            glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA);
        } else {
            glDisable(GL_BLEND);
        }
        glDepthMask(blend ? GL_FALSE : GL_TRUE);
        auto attribute = [](GLuint index, GLuint buffer, GLint components) {
            if (!buffer) return p_glDisableVertexAttribArray(index);
            p_glEnableVertexAttribArray(index);
            p_glBindBuffer(GL_ARRAY_BUFFER, buffer);
            p_glVertexAttribPointer(index, components, GL_FLOAT, GL_FALSE, 0, nullptr);
        };
        attribute(0, b.positions, 3);
        attribute(1, b.normals, 3);
        attribute(2, b.colors, 3);
        attribute(3, b.uvs, 2);
        attribute(4, b.tangents, 4);
        p_glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, b.indices);
        glDrawElements(GL_TRIANGLES, b.indexCount, GL_UNSIGNED_INT, nullptr);
    }
    glDepthMask(GL_TRUE);
    if (m.fbo) {  // resolve into the OSMesa buffer
        p_glBindFramebuffer(GL_READ_FRAMEBUFFER, m.fbo);
        p_glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
        p_glBlitFramebuffer(0, 0, m.width, m.height, 0, 0, m.width, m.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    }
    glFinish();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

double LlvmpipePeer::renderDepthFrame(const scene::Scene& scene) {
    Impl& m = *impl_;
    if (!m.depthProgram) {  // compiled before the clock starts: the first (warm-up) frame pays it
        m.depthProgram = p_glCreateProgram();
        p_glAttachShader(m.depthProgram,
                         compile(GL_VERTEX_SHADER, "#version 120\nattribute vec3 position; uniform mat4 clipFromWorld;\n"
                                                   "void main() { gl_Position = clipFromWorld * vec4(position, 1.0); }"));
        p_glAttachShader(m.depthProgram, compile(GL_FRAGMENT_SHADER, "#version 120\nvoid main() {}"));
        p_glBindAttribLocation(m.depthProgram, 0, "position");
        p_glLinkProgram(m.depthProgram);
        m.depthClipFromWorld = p_glGetUniformLocation(m.depthProgram, "clipFromWorld");
    }
    const auto t0 = std::chrono::steady_clock::now();
    const glm::mat4 clipFromWorld = glClipFromWorld(scene, m.width, m.height);
    if (m.fbo) p_glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glDepthMask(GL_TRUE);
    glDisable(GL_BLEND);
    glClear(GL_DEPTH_BUFFER_BIT);
    p_glUseProgram(m.depthProgram);
    p_glUniformMatrix4fv(m.depthClipFromWorld, 1, GL_FALSE, glm::value_ptr(clipFromWorld));
    for (GLuint index = 1; index < 5; ++index) p_glDisableVertexAttribArray(index);
    p_glEnableVertexAttribArray(0);
    for (size_t i = 0; i < m.meshes.size(); ++i) {
        const MeshBuffers& b = m.meshes[i];
        setCulling(scene, scene.meshes[i]);
        p_glBindBuffer(GL_ARRAY_BUFFER, b.positions);
        p_glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
        p_glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, b.indices);
        glDrawElements(GL_TRIANGLES, b.indexCount, GL_UNSIGNED_INT, nullptr);
    }
    glFinish();
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    glColorMask(GL_TRUE, GL_TRUE, GL_TRUE, GL_TRUE);
    return ms;
}

std::vector<bool> LlvmpipePeer::depthCoverage() const {
    const Impl& m = *impl_;
    std::vector<float> depth(size_t(m.width) * m.height);
    glReadPixels(0, 0, m.width, m.height, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
    std::vector<bool> covered(depth.size());
    for (size_t i = 0; i < depth.size(); ++i) covered[i] = depth[i] < 1.0f;
    return covered;
}

}  // namespace cuberille::bench
