#include "lockstep/runtime/yaml_config.h"

#include <algorithm>
#include <fstream>
#include <sstream>

namespace lockstep {

int YamlLine(const YAML::Node& n) {
  if (!n.IsDefined() || n.Mark().is_null()) return 0;
  return n.Mark().line + 1;
}

YamlMap::YamlMap(const YAML::Node& node, std::string where, std::string path)
    : node_(node), where_(std::move(where)), path_(std::move(path)) {
  if (node_ && !node_.IsNull() && !node_.IsMap()) {
    std::ostringstream msg;
    msg << where_ << ":" << YamlLine(node_) << ": '" << (path_.empty() ? "(top level)" : path_)
        << "' must be a map of keys";
    throw InputError(msg.str());
  }
}

std::string YamlMap::PathOf(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

YAML::Node YamlMap::Lookup(const std::string& key) {
  if (std::find(used_.begin(), used_.end(), key) == used_.end()) used_.push_back(key);
  if (!node_ || !node_.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  // Iterate instead of operator[] so a missing key never inserts into the node.
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    if (it->first.Scalar() == key) return it->second;
  }
  return YAML::Node(YAML::NodeType::Undefined);
}

YamlMap YamlMap::Map(const std::string& key) { return YamlMap(Lookup(key), where_, PathOf(key)); }

std::string YamlMap::Scalar(const YAML::Node& n) {
  if (n.IsScalar()) return n.Scalar();
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a map";
  return "nothing";
}

void YamlMap::Fail(const YAML::Node& at, const std::string& key, const std::string& what) const {
  std::ostringstream msg;
  msg << where_ << ":" << YamlLine(at) << ": key '" << PathOf(key) << "' " << what;
  throw InputError(msg.str());
}

void YamlMap::Finish() const {
  if (!node_ || !node_.IsMap()) return;
  for (auto it = node_.begin(); it != node_.end(); ++it) {
    const std::string key = it->first.Scalar();
    if (std::find(used_.begin(), used_.end(), key) != used_.end()) continue;
    std::ostringstream msg;
    msg << where_ << ":" << YamlLine(it->first) << ": unknown key '" << PathOf(key) << "'";
    if (!used_.empty()) {
      msg << " (known keys here:";
      for (const auto& k : used_) msg << " " << k;
      msg << ")";
    }
    throw InputError(msg.str());
  }
}

YAML::Node LoadYamlString(const std::string& text, const std::string& name) {
  try {
    return YAML::Load(text);
  } catch (const YAML::ParserException& e) {
    std::ostringstream msg;
    msg << name << ":" << e.mark.line + 1 << ": YAML syntax error: " << e.msg;
    throw InputError(msg.str());
  }
}

YAML::Node LoadYamlFile(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw InputError(file + ": cannot open config file");
  std::stringstream ss;
  ss << in.rdbuf();
  return LoadYamlString(ss.str(), file);
}

}  // namespace lockstep
