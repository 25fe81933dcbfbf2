#include "gl_util.h"

#include <stdexcept>
#include <vector>

namespace lockstep::render::gl {
namespace {

GLuint Compile(GLenum type, const std::string& src, const std::string& what) {
  const GLuint s = glCreateShader(type);
  const char* p = src.c_str();
  glShaderSource(s, 1, &p, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &n);
    std::vector<char> log(static_cast<std::size_t>(n) + 1);
    glGetShaderInfoLog(s, n, nullptr, log.data());
    glDeleteShader(s);
    throw std::runtime_error(what + (type == GL_VERTEX_SHADER ? " vertex" : " fragment") + " shader: " + log.data());
  }
  return s;
}

}  // namespace

GLuint BuildProgram(const std::string& vertex, const std::string& fragment, const std::string& what) {
  const GLuint vs = Compile(GL_VERTEX_SHADER, vertex, what), fs = Compile(GL_FRAGMENT_SHADER, fragment, what);
  const GLuint p = glCreateProgram();
  glAttachShader(p, vs);
  glAttachShader(p, fs);
  glLinkProgram(p);
  glDeleteShader(vs);
  glDeleteShader(fs);
  GLint ok = 0;
  glGetProgramiv(p, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint n = 0;
    glGetProgramiv(p, GL_INFO_LOG_LENGTH, &n);
    std::vector<char> log(static_cast<std::size_t>(n) + 1);
    glGetProgramInfoLog(p, n, nullptr, log.data());
    throw std::runtime_error(what + " program: " + log.data());
  }
  return p;
}

}  // namespace lockstep::render::gl
