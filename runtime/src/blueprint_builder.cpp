#include "lockstep/runtime/blueprint_builder.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <sstream>
#include <type_traits>

namespace lockstep::blueprint {
namespace {

msg::AttributeDeclaration Base(const std::string& id, msg::AttributeType type, const std::string& def, double min,
                               double max, bool modifiable) {
  msg::AttributeDeclaration a;
  a.id(id);
  a.type(type);
  a.default_value(def);
  a.min(min);
  a.max(max);
  a.restricted(false);
  a.modifiable(modifiable);
  return a;
}

void SetRecommended(msg::AttributeDeclaration& a, const std::vector<std::string>& values) {
  std::remove_cvref_t<decltype(a.recommended_values())> v;
  for (const auto& s : values) v.emplace_back(s);
  a.recommended_values(v);
}

std::string FormatNumber(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

bool ParseNumber(const std::string& s, double* out) {
  if (s.empty()) return false;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), *out);
  return ec == std::errc() && p == s.data() + s.size() && std::isfinite(*out);
}

const char* TypeName(msg::AttributeType t) {
  switch (t) {
    case msg::ATTR_BOOL: return "bool";
    case msg::ATTR_INT: return "int";
    case msg::ATTR_FLOAT: return "float";
    case msg::ATTR_STRING: return "string";
    case msg::ATTR_RGB: return "rgb";
  }
  return "?";
}

}  // namespace

msg::AttributeDeclaration Bool(const std::string& id, bool def, bool modifiable) {
  return Base(id, msg::ATTR_BOOL, def ? "true" : "false", -kInf, kInf, modifiable);
}

msg::AttributeDeclaration Int(const std::string& id, int64_t def, double min, double max, bool modifiable) {
  return Base(id, msg::ATTR_INT, std::to_string(def), min, max, modifiable);
}

msg::AttributeDeclaration Float(const std::string& id, double def, double min, double max, bool modifiable) {
  return Base(id, msg::ATTR_FLOAT, FormatNumber(def), min, max, modifiable);
}

msg::AttributeDeclaration String(const std::string& id, const std::string& def,
                                 const std::vector<std::string>& recommended, bool restricted, bool modifiable) {
  auto a = Base(id, msg::ATTR_STRING, def, -kInf, kInf, modifiable);
  SetRecommended(a, recommended);
  a.restricted(restricted);
  return a;
}

msg::AttributeDeclaration Rgb(const std::string& id, const std::string& def, const std::vector<std::string>& recommended,
                              bool modifiable) {
  auto a = Base(id, msg::ATTR_RGB, def, -kInf, kInf, modifiable);
  SetRecommended(a, recommended);
  return a;
}

msg::BlueprintDeclaration Make(const std::string& id, msg::ActorKind kind,
                               std::vector<msg::AttributeDeclaration> attributes, const std::string& tags,
                               double half_x, double half_y, double half_z) {
  msg::BlueprintDeclaration b;
  b.id(id);
  b.kind(kind);
  std::string t = tags;
  if (t.empty()) {
    t = id;
    std::replace(t.begin(), t.end(), '.', ',');
  }
  b.tags(t);
  msg::Vector3 e;
  e.x(half_x);
  e.y(half_y);
  e.z(half_z);
  b.half_extents(e);
  // CARLA: every modifiable attribute (an actor variation) has recommended values, the first
  // one its default; declarations that give none recommend their default.
  for (auto& a : attributes) {
    if (a.modifiable() && a.recommended_values().empty()) SetRecommended(a, {a.default_value().to_string()});
  }
  b.attributes(std::move(attributes));
  return b;
}

std::string CheckValue(const msg::AttributeDeclaration& decl, const std::string& value) {
  const std::string name = decl.id().to_string();
  auto bad = [&](const std::string& why) {
    return "attribute '" + name + "' (" + TypeName(decl.type()) + "): " + why + ", got '" + value + "'";
  };
  if (decl.restricted()) {
    const auto& r = decl.recommended_values();
    if (std::none_of(r.begin(), r.end(), [&](const auto& v) { return v.to_string() == value; })) {
      std::string opts;
      for (const auto& o : r) opts += (opts.empty() ? "" : ", ") + o.to_string();
      return bad("expected one of " + opts);
    }
  }
  double x = 0;
  switch (decl.type()) {
    case msg::ATTR_BOOL:
      if (value != "true" && value != "false" && value != "True" && value != "False") return bad("expected true or false");
      return {};
    case msg::ATTR_STRING:
      return {};
    case msg::ATTR_RGB: {
      std::stringstream ss(value);
      std::string part;
      int n = 0;
      while (std::getline(ss, part, ',')) {
        double c = 0;
        if (!ParseNumber(part, &c) || c < 0 || c > 255 || c != std::floor(c)) return bad("expected 'r,g,b' with 0..255 integers");
        ++n;
      }
      return n == 3 ? std::string() : bad("expected 'r,g,b'");
    }
    case msg::ATTR_INT:
      if (!ParseNumber(value, &x) || x != std::floor(x)) return bad("expected an integer");
      break;
    case msg::ATTR_FLOAT:
      if (!ParseNumber(value, &x)) return bad("expected a finite number");
      break;
  }
  if (x < decl.min() || x > decl.max()) {
    std::ostringstream r;
    r << "out of range [" << decl.min() << ", " << decl.max() << "]";
    return bad(r.str());
  }
  return {};
}

}  // namespace lockstep::blueprint
