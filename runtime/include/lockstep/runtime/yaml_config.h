#pragma once
// Reading YAML configs so that a mistake names its key and line. Each config struct
// has in-class defaults and a Load function that walks its map with YamlMap: Get
// reads optional keys, Require mandatory ones, Finish rejects keys nobody read.
#include <yaml-cpp/yaml.h>

#include <string>
#include <vector>

#include "lockstep/runtime/error.h"

namespace lockstep {

class YamlMap {
 public:
  // `where` prefixes messages, e.g. "launch.yaml"; `path` is the dotted key path of node.
  YamlMap(const YAML::Node& node, std::string where, std::string path);

  template <class T>
  bool Get(const std::string& key, T* out) {
    YAML::Node child = Lookup(key);
    if (!child) return false;
    try {
      *out = child.as<T>();
    } catch (const YAML::Exception&) {
      Fail(child, key, std::string("expected ") + TypeName<T>() + ", got '" + Scalar(child) + "'");
    }
    return true;
  }

  template <class T>
  void Require(const std::string& key, T* out) {
    if (!Get(key, out)) Fail(node_, key, "is required");
  }

  // A nested map or list; empty Node if absent.
  YAML::Node Child(const std::string& key) { return Lookup(key); }
  YamlMap Map(const std::string& key);
  std::string PathOf(const std::string& key) const;
  const std::string& where() const { return where_; }

  // Throws naming the first key that no Get/Require/Child call asked for.
  void Finish() const;

  [[noreturn]] void Fail(const YAML::Node& at, const std::string& key, const std::string& what) const;

 private:
  YAML::Node Lookup(const std::string& key);
  static std::string Scalar(const YAML::Node& n);
  template <class T>
  static const char* TypeName() {
    if constexpr (std::is_same_v<T, bool>) return "true or false";
    else if constexpr (std::is_integral_v<T>) return "an integer";
    else if constexpr (std::is_floating_point_v<T>) return "a number";
    else if constexpr (std::is_same_v<T, std::string>) return "a string";
    else return "a list";
  }

  YAML::Node node_;
  std::string where_;
  std::string path_;
  std::vector<std::string> used_;
};

// Line (1-based) of a node in its file, or 0 if unknown.
int YamlLine(const YAML::Node& n);

// Loads a file, turning parser errors into InputError with file and line.
YAML::Node LoadYamlFile(const std::string& file);
YAML::Node LoadYamlString(const std::string& text, const std::string& name);

}  // namespace lockstep
