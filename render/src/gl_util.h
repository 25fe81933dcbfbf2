#pragma once
// Small OpenGL helpers for the render core (program building, uniforms by name).
#define GL_GLEXT_PROTOTYPES 1
#include <GL/gl.h>
#include <GL/glext.h>

#include <string>
#include <unordered_map>

#include <Eigen/Core>

namespace lockstep::render::gl {

// Compiles and links; throws std::runtime_error with the info log.
GLuint BuildProgram(const std::string& vertex, const std::string& fragment, const std::string& what);

class Program {
 public:
  Program() = default;
  Program(GLuint id) : id_(id) {}
  GLuint id() const { return id_; }
  void Use() const { glUseProgram(id_); }
  GLint Loc(const char* name) {
    auto it = cache_.find(name);
    if (it != cache_.end()) return it->second;
    const GLint l = glGetUniformLocation(id_, name);
    cache_.emplace(name, l);
    return l;
  }
  void Set(const char* n, const Eigen::Matrix4f& m) { glUniformMatrix4fv(Loc(n), 1, GL_FALSE, m.data()); }
  void Set(const char* n, const Eigen::Vector3f& v) { glUniform3f(Loc(n), v.x(), v.y(), v.z()); }
  void Set(const char* n, const Eigen::Vector2f& v) { glUniform2f(Loc(n), v.x(), v.y()); }
  void Set(const char* n, float f) { glUniform1f(Loc(n), f); }
  void SetInt(const char* n, int i) { glUniform1i(Loc(n), i); }
  void SetUint(const char* n, unsigned u) { glUniform1ui(Loc(n), u); }

 private:
  GLuint id_ = 0;
  std::unordered_map<std::string, GLint> cache_;
};

}  // namespace lockstep::render::gl
