#include "bench/llvmpipe_peer.h"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <chrono>
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

const char* kVertexShader = R"(#version 120
attribute vec3 position; attribute vec3 normal;
uniform mat4 clipFromWorld;
varying vec3 vNormal;
void main() { vNormal = normal; gl_Position = clipFromWorld * vec4(position, 1.0); })";

// The same Lambert as raster/shade.h: albedo * (ambient + radiance * max(0, n.l)).
const char* kFragmentShader = R"(#version 120
uniform vec3 albedo, lightDir, radiance, ambient;
varying vec3 vNormal;
void main() {
  float c = max(0.0, dot(normalize(vNormal), lightDir));
  gl_FragColor = vec4(albedo * (ambient + radiance * c), 1.0);
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
    GLuint positions, normals, indices;
    GLsizei indexCount;
};

}  // namespace

struct LlvmpipePeer::Impl {
    int width, height, msaa;
    OSMesaContext context = nullptr;
    std::vector<unsigned char> buffer;
    GLuint program = 0, fbo = 0;
    std::vector<MeshBuffers> meshes;
};

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

    m.program = p_glCreateProgram();
    p_glAttachShader(m.program, compile(GL_VERTEX_SHADER, kVertexShader));
    p_glAttachShader(m.program, compile(GL_FRAGMENT_SHADER, kFragmentShader));
    p_glBindAttribLocation(m.program, 0, "position");
    p_glBindAttribLocation(m.program, 1, "normal");
    p_glLinkProgram(m.program);
    p_glUseProgram(m.program);

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
    for (const scene::Mesh& mesh : scene.meshes) {
        MeshBuffers b;
        p_glGenBuffers(1, &b.positions);
        p_glBindBuffer(GL_ARRAY_BUFFER, b.positions);
        p_glBufferData(GL_ARRAY_BUFFER, mesh.positions.size() * sizeof(glm::vec3), mesh.positions.data(), GL_STATIC_DRAW);
        p_glGenBuffers(1, &b.normals);
        p_glBindBuffer(GL_ARRAY_BUFFER, b.normals);
        p_glBufferData(GL_ARRAY_BUFFER, mesh.normals.size() * sizeof(glm::vec3), mesh.normals.data(), GL_STATIC_DRAW);
        p_glGenBuffers(1, &b.indices);
        p_glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, b.indices);
        p_glBufferData(GL_ELEMENT_ARRAY_BUFFER, mesh.indices.size() * sizeof(uint32_t), mesh.indices.data(), GL_STATIC_DRAW);
        b.indexCount = GLsizei(mesh.indices.size());
        impl_->meshes.push_back(b);
    }
    glFinish();
}

double LlvmpipePeer::renderFrame(const scene::Scene& scene) {
    Impl& m = *impl_;
    const auto t0 = std::chrono::steady_clock::now();
    // The same view as the clip-space draws, with OpenGL's [-1, 1] depth.
    const glm::mat4 clipFromWorld =
        glm::perspectiveRH_NO(glm::radians(scene.camera.verticalFovDegrees), float(m.width) / m.height,
                              scene.camera.nearPlane, scene.camera.farPlane) *
        scene.camera.viewFromWorld();
    if (m.fbo) p_glBindFramebuffer(GL_FRAMEBUFFER, m.fbo);
    glClearColor(scene.background.r, scene.background.g, scene.background.b, 1.0f);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    p_glUniformMatrix4fv(p_glGetUniformLocation(m.program, "clipFromWorld"), 1, GL_FALSE, glm::value_ptr(clipFromWorld));
    const glm::vec3 towardsLight = -scene.lighting.lights[0].direction;  // the bench scenes' one directional light
    p_glUniform3fv(p_glGetUniformLocation(m.program, "lightDir"), 1, glm::value_ptr(towardsLight));
    p_glUniform3fv(p_glGetUniformLocation(m.program, "radiance"), 1, glm::value_ptr(scene.lighting.lights[0].intensity));
    p_glUniform3fv(p_glGetUniformLocation(m.program, "ambient"), 1, glm::value_ptr(scene.lighting.ambient));
    const GLint albedo = p_glGetUniformLocation(m.program, "albedo");
    p_glEnableVertexAttribArray(0);
    p_glEnableVertexAttribArray(1);
    for (size_t i = 0; i < m.meshes.size(); ++i) {
        const MeshBuffers& b = m.meshes[i];
        p_glUniform3fv(albedo, 1, glm::value_ptr(scene.meshes[i].color));
        p_glBindBuffer(GL_ARRAY_BUFFER, b.positions);
        p_glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
        p_glBindBuffer(GL_ARRAY_BUFFER, b.normals);
        p_glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, 0, nullptr);
        p_glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, b.indices);
        glDrawElements(GL_TRIANGLES, b.indexCount, GL_UNSIGNED_INT, nullptr);
    }
    if (m.fbo) {  // resolve into the OSMesa buffer
        p_glBindFramebuffer(GL_READ_FRAMEBUFFER, m.fbo);
        p_glBindFramebuffer(GL_DRAW_FRAMEBUFFER, 0);
        p_glBlitFramebuffer(0, 0, m.width, m.height, 0, 0, m.width, m.height, GL_COLOR_BUFFER_BIT, GL_NEAREST);
    }
    glFinish();
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

}  // namespace cuberille::bench
