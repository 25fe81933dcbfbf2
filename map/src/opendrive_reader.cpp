#include "lockstep/map/opendrive_reader.h"

#include <pugixml.hpp>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <sstream>

#include "lockstep/map/road_profile.h"
#include "piecewise_cubic.h"

namespace lockstep::map {
namespace {

// Sanity limits: well above any real map, low enough that hostile input cannot make
// later sampling (meshes, spatial index) allocate without bound.
constexpr double kMaxLength = 1.0e5;       // one road (m)
constexpr double kMaxCoordinate = 1.0e7;   // (m)
constexpr int kMaxLanesPerSide = 64;

// OpenDRIVE <border>: a lane's outer edge as t from the reference line (positive
// left), independent of the lanes inside it. Turns borders into the equivalent width
// records (outer edge minus the inner neighbour's outer edge, the centre lane sitting
// at the road's laneOffset), so every later query reads widths only. A lane with
// <width> records keeps them (the standard gives width precedence).
void WidthsFromBorders(const Road& road, LaneSection* sec) {
  const bool any = std::any_of(sec->lanes.begin(), sec->lanes.end(),
                               [](const Lane& l) { return l.widths.empty() && !l.borders.empty(); });
  if (!any) return;
  for (const int side : {1, -1}) {
    std::vector<Poly3> inner = RebasePoly3s(road.lane_offset, sec->s);  // t of the centre lane
    for (int id = side;; id += side) {
      Lane* lane = sec->Find(id);
      if (!lane) break;
      std::vector<Poly3> outer;
      if (!lane->widths.empty()) {
        outer = CombinePoly3s(inner, RebasePoly3s(lane->widths, 0.0), side);
      } else if (!lane->borders.empty()) {
        outer = RebasePoly3s(lane->borders, 0.0);
        lane->widths = CombinePoly3s(outer, inner, -1.0);  // left: outer - inner
        if (side < 0)                                      // right: inner - outer
          for (Poly3& w : lane->widths) w = Poly3{w.s, -w.a, -w.b, -w.c, -w.d};
      } else {
        outer = inner;
      }
      inner = std::move(outer);
    }
  }
}

class Reader {
 public:
  Reader(std::string_view xml, std::string source) : xml_(xml), source_(std::move(source)) {
    for (std::size_t i = 0; i < xml_.size(); ++i)
      if (xml_[i] == '\n') line_starts_.push_back(i + 1);
  }

  OpenDrive Parse() {
    pugi::xml_document doc;
    const pugi::xml_parse_result res =
        doc.load_buffer(xml_.data(), xml_.size(), pugi::parse_default, pugi::encoding_utf8);
    if (!res) {
      std::ostringstream os;
      os << source_ << ":" << LineOf(static_cast<std::ptrdiff_t>(res.offset)) << ": XML error: "
         << res.description();
      throw MapError(os.str());
    }
    const pugi::xml_node root = doc.child("OpenDRIVE");
    if (!root) {
      const pugi::xml_node first = doc.first_child();
      Fail(first ? first : doc, "document has no <OpenDRIVE> root element");
    }
    OpenDrive od;
    ReadHeader(root, &od.header);
    for (pugi::xml_node n = root.child("road"); n; n = n.next_sibling("road")) {
      od.roads.push_back(ReadRoad(n));
      const Road& r = od.roads.back();
      if (!od.road_index.emplace(r.id, static_cast<int>(od.roads.size() - 1)).second)
        Fail(n, "duplicate road id '" + r.id + "'");
    }
    for (pugi::xml_node n = root.child("junction"); n; n = n.next_sibling("junction")) {
      od.junctions.push_back(ReadJunction(n));
      if (!od.junction_index.emplace(od.junctions.back().id, static_cast<int>(od.junctions.size() - 1)).second)
        Fail(n, "duplicate junction id '" + od.junctions.back().id + "'");
    }
    for (pugi::xml_node n = root.child("controller"); n; n = n.next_sibling("controller")) {
      Controller c;
      c.id = Req(n, "id");
      c.name = n.attribute("name").value();
      for (pugi::xml_node k = n.child("control"); k; k = k.next_sibling("control")) c.signal_ids.push_back(Req(k, "signalId"));
      od.controllers.push_back(std::move(c));
    }
    std::size_t i = 0;
    for (pugi::xml_node n = root.child("road"); n; n = n.next_sibling("road"), ++i) {
      Road& r = od.roads[i];
      if (r.junction != "-1" && !r.junction.empty()) {
        auto it = od.junction_index.find(r.junction);
        if (it == od.junction_index.end()) Fail(n, "road '" + r.id + "' refers to unknown junction '" + r.junction + "'");
        r.junction_index = it->second;
      }
    }
    return od;
  }

 private:
  std::size_t LineOf(std::ptrdiff_t offset) const {
    if (offset < 0) return 0;
    auto it = std::upper_bound(line_starts_.begin(), line_starts_.end(), static_cast<std::size_t>(offset));
    return static_cast<std::size_t>(it - line_starts_.begin());
  }

  [[noreturn]] void Fail(const pugi::xml_node& n, const std::string& what) const {
    std::ostringstream os;
    os << source_ << ":" << LineOf(n.offset_debug()) << ": <" << (n.name()[0] ? n.name() : "document")
       << ">: " << what;
    throw MapError(os.str());
  }

  std::string Req(const pugi::xml_node& n, const char* name) const {
    const pugi::xml_attribute a = n.attribute(name);
    if (!a) Fail(n, std::string("missing attribute '") + name + "'");
    return a.value();
  }

  double ToNumber(const pugi::xml_node& n, const char* name, const char* text) const {
    const char* p = text;
    while (*p == ' ' || *p == '\t' || *p == '\n' || *p == '\r') ++p;
    char* end = nullptr;
    errno = 0;
    const double v = std::strtod(p, &end);
    if (end == p) Fail(n, std::string("attribute '") + name + "' is not a number: '" + text + "'");
    while (*end == ' ' || *end == '\t' || *end == '\n' || *end == '\r') ++end;
    if (*end != '\0') Fail(n, std::string("attribute '") + name + "' is not a number: '" + text + "'");
    if (!std::isfinite(v) || std::fabs(v) > kMaxCoordinate)
      Fail(n, std::string("attribute '") + name + "' is out of range: '" + text + "'");
    return v;
  }

  double Num(const pugi::xml_node& n, const char* name) const {
    const pugi::xml_attribute a = n.attribute(name);
    if (!a) Fail(n, std::string("missing attribute '") + name + "'");
    return ToNumber(n, name, a.value());
  }

  double Opt(const pugi::xml_node& n, const char* name, double fallback) const {
    const pugi::xml_attribute a = n.attribute(name);
    if (!a || a.value()[0] == '\0') return fallback;
    return ToNumber(n, name, a.value());
  }

  int Int(const pugi::xml_node& n, const char* name) const {
    const double v = Num(n, name);
    if (v != std::floor(v) || std::fabs(v) > 1e6) Fail(n, std::string("attribute '") + name + "' is not an integer");
    return static_cast<int>(v);
  }

  double Length(const pugi::xml_node& n, const char* name) const {
    const double v = Num(n, name);
    if (v < 0 || v > kMaxLength) Fail(n, std::string("attribute '") + name + "' is not a length in [0, 1e5] m");
    return v;
  }

  static double SpeedToMps(double v, const std::string& unit) {
    if (unit == "mph") return v * 0.44704;
    if (unit == "km/h") return v / 3.6;
    return v;  // OpenDRIVE default unit is m/s
  }

  Poly3 ReadPoly(const pugi::xml_node& n, const char* s_name) const {
    return Poly3{Num(n, s_name), Num(n, "a"), Num(n, "b"), Num(n, "c"), Num(n, "d")};
  }

  void ReadHeader(const pugi::xml_node& root, Header* h) const {
    const pugi::xml_node n = root.child("header");
    if (!n) Fail(root, "missing <header>");
    h->rev_major = static_cast<int>(Opt(n, "revMajor", 1));
    h->rev_minor = static_cast<int>(Opt(n, "revMinor", 4));
    h->name = n.attribute("name").value();
    h->version = n.attribute("version").value();
    h->date = n.attribute("date").value();
    h->vendor = n.attribute("vendor").value();
    h->north = Opt(n, "north", 0);
    h->south = Opt(n, "south", 0);
    h->east = Opt(n, "east", 0);
    h->west = Opt(n, "west", 0);
    h->geo_reference = n.child("geoReference").text().get();
    auto trim = [](std::string& s) {
      while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.pop_back();
      std::size_t i = 0;
      while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
      s.erase(0, i);
    };
    trim(h->geo_reference);
  }

  RoadLink ReadLink(const pugi::xml_node& n) const {
    RoadLink l;
    if (!n) return l;
    const std::string type = n.attribute("elementType").value();
    if (type == "road") l.kind = RoadLink::Kind::Road;
    else if (type == "junction") l.kind = RoadLink::Kind::Junction;
    else Fail(n, "elementType must be 'road' or 'junction', got '" + type + "'");
    l.element_id = Req(n, "elementId");
    l.contact = ReadContact(n, "contactPoint", l.kind == RoadLink::Kind::Road);
    return l;
  }

  ContactPoint ReadContact(const pugi::xml_node& n, const char* name, bool required) const {
    const pugi::xml_attribute a = n.attribute(name);
    if (!a) {
      if (required) Fail(n, std::string("missing attribute '") + name + "'");
      return ContactPoint::None;
    }
    const std::string v = a.value();
    if (v == "start") return ContactPoint::Start;
    if (v == "end") return ContactPoint::End;
    Fail(n, std::string("attribute '") + name + "' must be 'start' or 'end', got '" + v + "'");
  }

  Geometry ReadGeometry(const pugi::xml_node& n) const {
    Geometry g;
    g.s = Num(n, "s");
    g.x = Num(n, "x");
    g.y = Num(n, "y");
    g.hdg = Num(n, "hdg");
    g.length = Length(n, "length");
    const pugi::xml_node k = n.first_child();
    if (!k) Fail(n, "geometry record has no shape (line, arc, spiral, poly3, paramPoly3)");
    const std::string kind = k.name();
    if (kind == "line") {
      g.kind = GeometryKind::Line;
    } else if (kind == "arc") {
      g.kind = GeometryKind::Arc;
      g.curvature = Num(k, "curvature");
    } else if (kind == "spiral") {
      g.kind = GeometryKind::Spiral;
      g.curv_start = Num(k, "curvStart");
      g.curv_end = Num(k, "curvEnd");
    } else if (kind == "poly3") {
      g.kind = GeometryKind::Poly3;
      g.a = Num(k, "a"); g.b = Num(k, "b"); g.c = Num(k, "c"); g.d = Num(k, "d");
    } else if (kind == "paramPoly3") {
      g.kind = GeometryKind::ParamPoly3;
      g.au = Num(k, "aU"); g.bu = Num(k, "bU"); g.cu = Num(k, "cU"); g.du = Num(k, "dU");
      g.av = Num(k, "aV"); g.bv = Num(k, "bV"); g.cv = Num(k, "cV"); g.dv = Num(k, "dV");
      // A missing pRange means "normalized" (OpenDRIVE 1.4, where p ran over [0, 1], and CARLA).
      const std::string range = k.attribute("pRange").value();
      if (range == "arcLength") g.p_range_normalized = false;
      else if (range.empty() || range == "normalized") g.p_range_normalized = true;
      else Fail(k, "pRange must be 'arcLength' or 'normalized', got '" + range + "'");
    } else {
      Fail(k, "unknown geometry shape <" + kind + ">");
    }
    PrepareGeometry(g);
    return g;
  }

  static LaneType ParseLaneType(const std::string& t) {
    static const std::pair<const char*, LaneType> kTypes[] = {
        {"none", LaneType::None}, {"driving", LaneType::Driving}, {"stop", LaneType::Stop},
        {"shoulder", LaneType::Shoulder}, {"biking", LaneType::Biking}, {"sidewalk", LaneType::Sidewalk},
        {"walking", LaneType::Sidewalk}, {"border", LaneType::Border}, {"restricted", LaneType::Restricted},
        {"parking", LaneType::Parking}, {"bidirectional", LaneType::Bidirectional},
        {"median", LaneType::Median}, {"special1", LaneType::Special1}, {"special2", LaneType::Special2},
        {"special3", LaneType::Special3}, {"roadWorks", LaneType::RoadWorks}, {"tram", LaneType::Tram},
        {"rail", LaneType::Rail}, {"entry", LaneType::Entry}, {"exit", LaneType::Exit},
        {"offRamp", LaneType::OffRamp}, {"onRamp", LaneType::OnRamp}, {"curb", LaneType::Border},
        {"connectingRamp", LaneType::OnRamp}, {"slipLane", LaneType::Driving}, {"bus", LaneType::Driving},
        {"taxi", LaneType::Driving}, {"HOV", LaneType::Driving}, {"mwyEntry", LaneType::Entry},
        {"mwyExit", LaneType::Exit}, {"bicycle", LaneType::Biking}, {"sharedWalkway", LaneType::Sidewalk}};
    for (const auto& [name, type] : kTypes)
      if (t == name) return type;
    return LaneType::None;
  }

  RoadMark ReadMark(const pugi::xml_node& n) const {
    RoadMark m;
    m.s_offset = Num(n, "sOffset");
    const std::string type = Req(n, "type");
    static const std::pair<const char*, RoadMarkType> kTypes[] = {
        {"none", RoadMarkType::None}, {"solid", RoadMarkType::Solid}, {"broken", RoadMarkType::Broken},
        {"solid solid", RoadMarkType::SolidSolid}, {"solid broken", RoadMarkType::SolidBroken},
        {"broken solid", RoadMarkType::BrokenSolid}, {"broken broken", RoadMarkType::BrokenBroken},
        {"botts dots", RoadMarkType::BottsDots}, {"grass", RoadMarkType::Grass}, {"curb", RoadMarkType::Curb},
        {"custom", RoadMarkType::Custom}, {"edge", RoadMarkType::Edge}, {"", RoadMarkType::None}};
    m.type = RoadMarkType::Custom;
    for (const auto& [name, t] : kTypes)
      if (type == name) m.type = t;
    const std::string color = n.attribute("color").value();
    static const std::pair<const char*, RoadMarkColor> kColors[] = {
        {"standard", RoadMarkColor::Standard}, {"white", RoadMarkColor::White}, {"yellow", RoadMarkColor::Yellow},
        {"blue", RoadMarkColor::Blue}, {"green", RoadMarkColor::Green}, {"red", RoadMarkColor::Red},
        {"orange", RoadMarkColor::Orange}, {"black", RoadMarkColor::Black}, {"violet", RoadMarkColor::Violet}};
    for (const auto& [name, c] : kColors)
      if (color == name) m.color = c;
    m.width = Opt(n, "width", m.type == RoadMarkType::None ? 0.0 : 0.15);
    m.material = n.attribute("material").value();
    const pugi::xml_attribute lc = n.attribute("laneChange");
    if (lc) {
      const std::string v = lc.value();
      if (v == "none") m.lane_change = MarkLaneChange::None;
      else if (v == "increase") m.lane_change = MarkLaneChange::Increase;
      else if (v == "decrease") m.lane_change = MarkLaneChange::Decrease;
      else m.lane_change = MarkLaneChange::Both;
    } else {
      // Spec default is "both"; a continuous line or a curb nevertheless forbids crossing.
      const bool solid = m.type == RoadMarkType::Solid || m.type == RoadMarkType::SolidSolid ||
                         m.type == RoadMarkType::Curb || m.type == RoadMarkType::Grass;
      m.lane_change = solid ? MarkLaneChange::None : MarkLaneChange::Both;
    }
    return m;
  }

  Lane ReadLane(const pugi::xml_node& n) const {
    Lane l;
    l.id = Int(n, "id");
    l.type = ParseLaneType(Req(n, "type"));
    const std::string level = n.attribute("level").value();
    l.level = level == "true" || level == "1";
    if (const pugi::xml_node link = n.child("link")) {
      for (pugi::xml_node p = link.child("predecessor"); p; p = p.next_sibling("predecessor")) l.predecessors.push_back(Int(p, "id"));
      for (pugi::xml_node p = link.child("successor"); p; p = p.next_sibling("successor")) l.successors.push_back(Int(p, "id"));
    }
    for (pugi::xml_node w = n.child("width"); w; w = w.next_sibling("width")) l.widths.push_back(ReadPoly(w, "sOffset"));
    std::stable_sort(l.widths.begin(), l.widths.end(), [](const Poly3& a, const Poly3& b) { return a.s < b.s; });
    // <border>: the outer edge's t; turned into widths once the whole road is read.
    for (pugi::xml_node b = n.child("border"); b; b = b.next_sibling("border")) l.borders.push_back(ReadPoly(b, "sOffset"));
    std::stable_sort(l.borders.begin(), l.borders.end(), [](const Poly3& a, const Poly3& b) { return a.s < b.s; });
    for (pugi::xml_node m = n.child("roadMark"); m; m = m.next_sibling("roadMark")) l.marks.push_back(ReadMark(m));
    std::stable_sort(l.marks.begin(), l.marks.end(), [](const RoadMark& a, const RoadMark& b) { return a.s_offset < b.s_offset; });
    if (const pugi::xml_node sp = n.child("speed")) {
      l.speed_max_mps = SpeedToMps(Num(sp, "max"), sp.attribute("unit").value());
    }
    return l;
  }

  LaneSection ReadSection(const pugi::xml_node& n) const {
    LaneSection sec;
    sec.s = Num(n, "s");
    int sides = 0;
    for (const char* side : {"left", "center", "right"}) {
      const pugi::xml_node group = n.child(side);
      if (!group) continue;
      ++sides;
      int count = 0;
      for (pugi::xml_node l = group.child("lane"); l; l = l.next_sibling("lane")) {
        Lane lane = ReadLane(l);
        const std::string s = side;
        if ((s == "left" && lane.id <= 0) || (s == "right" && lane.id >= 0) || (s == "center" && lane.id != 0))
          Fail(l, "lane id " + std::to_string(lane.id) + " does not belong in <" + s + ">");
        if (++count > kMaxLanesPerSide) Fail(l, "too many lanes");
        sec.lanes.push_back(std::move(lane));
      }
    }
    if (sides == 0) Fail(n, "lane section has no <left>, <center> or <right>");
    std::sort(sec.lanes.begin(), sec.lanes.end(), [](const Lane& a, const Lane& b) { return a.id > b.id; });
    const bool has_center = std::any_of(sec.lanes.begin(), sec.lanes.end(), [](const Lane& l) { return l.id == 0; });
    if (!has_center) {
      Lane c;
      sec.lanes.push_back(c);
      std::sort(sec.lanes.begin(), sec.lanes.end(), [](const Lane& a, const Lane& b) { return a.id > b.id; });
    }
    for (std::size_t i = 0; i + 1 < sec.lanes.size(); ++i) {
      if (sec.lanes[i].id == sec.lanes[i + 1].id) Fail(n, "duplicate lane id " + std::to_string(sec.lanes[i].id));
    }
    // Ids must be contiguous so that LaneSection::Find can index directly.
    sec.left_count = static_cast<int>(std::count_if(sec.lanes.begin(), sec.lanes.end(), [](const Lane& l) { return l.id > 0; }));
    const int right_count = static_cast<int>(sec.lanes.size()) - sec.left_count - 1;
    if (sec.lanes.front().id != sec.left_count || sec.lanes.back().id != -right_count)
      Fail(n, "lane ids are not contiguous (expected 1..n on the left, -1..-m on the right)");
    return sec;
  }

  Road ReadRoad(const pugi::xml_node& n) const {
    Road r;
    r.id = Req(n, "id");
    r.name = n.attribute("name").value();
    r.length = Length(n, "length");
    r.junction = n.attribute("junction") ? n.attribute("junction").value() : "-1";
    if (const pugi::xml_node link = n.child("link")) {
      r.predecessor = ReadLink(link.child("predecessor"));
      r.successor = ReadLink(link.child("successor"));
    }
    for (pugi::xml_node t = n.child("type"); t; t = t.next_sibling("type")) {
      RoadTypeRecord rec;
      rec.s = Num(t, "s");
      rec.type = t.attribute("type").value();
      if (const pugi::xml_node sp = t.child("speed")) {
        const std::string max = sp.attribute("max").value();
        if (max != "no limit" && max != "undefined") rec.speed_max_mps = SpeedToMps(Num(sp, "max"), sp.attribute("unit").value());
      }
      r.types.push_back(rec);
    }
    const pugi::xml_node pv = n.child("planView");
    if (!pv) Fail(n, "road '" + r.id + "' has no <planView>");
    for (pugi::xml_node g = pv.child("geometry"); g; g = g.next_sibling("geometry")) r.plan_view.push_back(ReadGeometry(g));
    if (r.plan_view.empty()) Fail(pv, "road '" + r.id + "' has no <geometry>");
    std::stable_sort(r.plan_view.begin(), r.plan_view.end(), [](const Geometry& a, const Geometry& b) { return a.s < b.s; });
    if (const pugi::xml_node ep = n.child("elevationProfile"))
      for (pugi::xml_node e = ep.child("elevation"); e; e = e.next_sibling("elevation")) r.elevation.push_back(ReadPoly(e, "s"));
    std::stable_sort(r.elevation.begin(), r.elevation.end(), [](const Poly3& a, const Poly3& b) { return a.s < b.s; });
    const pugi::xml_node lanes = n.child("lanes");
    if (!lanes) Fail(n, "road '" + r.id + "' has no <lanes>");
    for (pugi::xml_node o = lanes.child("laneOffset"); o; o = o.next_sibling("laneOffset")) r.lane_offset.push_back(ReadPoly(o, "s"));
    std::stable_sort(r.lane_offset.begin(), r.lane_offset.end(), [](const Poly3& a, const Poly3& b) { return a.s < b.s; });
    for (pugi::xml_node s = lanes.child("laneSection"); s; s = s.next_sibling("laneSection")) r.sections.push_back(ReadSection(s));
    if (r.sections.empty()) Fail(lanes, "road '" + r.id + "' has no <laneSection>");
    std::stable_sort(r.sections.begin(), r.sections.end(), [](const LaneSection& a, const LaneSection& b) { return a.s < b.s; });
    for (std::size_t i = 0; i < r.sections.size(); ++i) {
      LaneSection& sec = r.sections[i];
      sec.s = std::clamp(sec.s, 0.0, r.length);
      const double end = i + 1 < r.sections.size() ? std::clamp(r.sections[i + 1].s, 0.0, r.length) : r.length;
      sec.length = std::max(0.0, end - sec.s);
    }
    for (LaneSection& sec : r.sections) WidthsFromBorders(r, &sec);
    if (const pugi::xml_node sigs = n.child("signals")) {
      for (pugi::xml_node s = sigs.child("signal"); s; s = s.next_sibling("signal")) r.signals.push_back(ReadSignal(s));
      for (pugi::xml_node s = sigs.child("signalReference"); s; s = s.next_sibling("signalReference")) {
        SignalReference ref;
        ref.id = Req(s, "id");
        ref.s = Num(s, "s");
        ref.t = Num(s, "t");
        ref.orientation = s.attribute("orientation").value();
        for (pugi::xml_node v = s.child("validity"); v; v = v.next_sibling("validity"))
          ref.validity.emplace_back(Int(v, "fromLane"), Int(v, "toLane"));
        r.signal_refs.push_back(ref);
      }
    }
    if (const pugi::xml_node objs = n.child("objects"))
      for (pugi::xml_node o = objs.child("object"); o; o = o.next_sibling("object")) r.objects.push_back(ReadObject(o));
    PlaceSignalsAndObjects(&r);
    return r;
  }

  Signal ReadSignal(const pugi::xml_node& n) const {
    Signal s;
    s.id = Req(n, "id");
    s.name = n.attribute("name").value();
    s.s = Num(n, "s");
    s.t = Num(n, "t");
    s.z_offset = Opt(n, "zOffset", 0);
    s.h_offset = Opt(n, "hOffset", 0);
    s.height = Opt(n, "height", 0);
    s.width = Opt(n, "width", 0);
    s.orientation = n.attribute("orientation").value();
    const std::string dyn = n.attribute("dynamic").value();
    s.dynamic = dyn == "yes" || dyn == "true";
    s.country = n.attribute("country").value();
    s.type = n.attribute("type").value();
    s.subtype = n.attribute("subtype").value();
    s.unit = n.attribute("unit").value();
    s.text = n.attribute("text").value();
    s.value = Opt(n, "value", std::numeric_limits<double>::quiet_NaN());
    for (pugi::xml_node v = n.child("validity"); v; v = v.next_sibling("validity"))
      s.validity.emplace_back(Int(v, "fromLane"), Int(v, "toLane"));
    return s;
  }

  RoadObject ReadObject(const pugi::xml_node& n) const {
    RoadObject o;
    o.id = Req(n, "id");
    o.name = n.attribute("name").value();
    o.type = n.attribute("type").value();
    o.s = Num(n, "s");
    o.t = Num(n, "t");
    o.z_offset = Opt(n, "zOffset", 0);
    o.hdg = Opt(n, "hdg", 0);
    o.length = Opt(n, "length", 0);
    o.width = Opt(n, "width", 0);
    o.height = Opt(n, "height", 0);
    o.radius = Opt(n, "radius", 0);
    auto read_outline = [&](const pugi::xml_node& outline) {
      for (pugi::xml_node c = outline.child("cornerLocal"); c; c = c.next_sibling("cornerLocal"))
        o.outline_local.emplace_back(Num(c, "u"), Num(c, "v"));
      for (pugi::xml_node c = outline.child("cornerRoad"); c; c = c.next_sibling("cornerRoad"))
        o.outline_road.emplace_back(Num(c, "s"), Num(c, "t"));
    };
    if (const pugi::xml_node outline = n.child("outline")) read_outline(outline);
    if (const pugi::xml_node outlines = n.child("outlines"))  // OpenDRIVE 1.5+
      for (pugi::xml_node ol = outlines.child("outline"); ol; ol = ol.next_sibling("outline")) read_outline(ol);
    return o;
  }

  Junction ReadJunction(const pugi::xml_node& n) const {
    Junction j;
    j.id = Req(n, "id");
    j.name = n.attribute("name").value();
    for (pugi::xml_node c = n.child("connection"); c; c = c.next_sibling("connection")) {
      Connection con;
      con.id = c.attribute("id").value();
      con.incoming_road = Req(c, "incomingRoad");
      con.connecting_road = c.attribute("connectingRoad") ? c.attribute("connectingRoad").value()
                                                          : Req(c, "linkedRoad");  // 1.7 direct junctions
      const pugi::xml_attribute cp = c.attribute("contactPoint");
      con.contact = cp ? ReadContact(c, "contactPoint", true) : ContactPoint::Start;
      for (pugi::xml_node l = c.child("laneLink"); l; l = l.next_sibling("laneLink"))
        con.lane_links.emplace_back(Int(l, "from"), Int(l, "to"));
      j.connections.push_back(std::move(con));
    }
    for (pugi::xml_node c = n.child("controller"); c; c = c.next_sibling("controller")) j.controllers.push_back(Req(c, "id"));
    return j;
  }

  static void PlaceSignalsAndObjects(Road* r) {
    for (Signal& s : r->signals) {
      double hdg = 0;
      const Eigen::Vector3d p = RoadToWorld(*r, std::clamp(s.s, 0.0, r->length), s.t, &hdg);
      s.x = p.x();
      s.y = p.y();
      s.z = p.z() + s.z_offset;
      // A sign faces traffic: orientation "+" serves lanes driving with s, so it faces -s.
      s.yaw = hdg + s.h_offset + (s.orientation == "-" ? 0.0 : std::numbers::pi);
    }
    for (RoadObject& o : r->objects) {
      double hdg = 0;
      const Eigen::Vector3d p = RoadToWorld(*r, std::clamp(o.s, 0.0, r->length), o.t, &hdg);
      o.x = p.x();
      o.y = p.y();
      o.z = p.z() + o.z_offset;
      o.yaw = hdg + o.hdg;
    }
  }

  std::string_view xml_;
  std::string source_;
  std::vector<std::size_t> line_starts_{0};
};

}  // namespace

OpenDrive ParseOpenDrive(std::string_view xml, const std::string& source) {
  return Reader(xml, source).Parse();
}

OpenDrive LoadOpenDriveFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MapError(path + ": cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  const std::string text = ss.str();
  const std::size_t slash = path.find_last_of('/');
  return ParseOpenDrive(text, slash == std::string::npos ? path : path.substr(slash + 1));
}

const char* ToString(LaneType t) {
  switch (t) {
    case LaneType::None: return "None";
    case LaneType::Driving: return "Driving";
    case LaneType::Stop: return "Stop";
    case LaneType::Shoulder: return "Shoulder";
    case LaneType::Biking: return "Biking";
    case LaneType::Sidewalk: return "Sidewalk";
    case LaneType::Border: return "Border";
    case LaneType::Restricted: return "Restricted";
    case LaneType::Parking: return "Parking";
    case LaneType::Bidirectional: return "Bidirectional";
    case LaneType::Median: return "Median";
    case LaneType::Entry: return "Entry";
    case LaneType::Exit: return "Exit";
    case LaneType::OffRamp: return "OffRamp";
    case LaneType::OnRamp: return "OnRamp";
    default: return "Other";
  }
}

const char* ToString(RoadMarkType t) {
  static const char* kNames[] = {"None", "Solid", "Broken", "SolidSolid", "SolidBroken", "BrokenSolid",
                                 "BrokenBroken", "BottsDots", "Grass", "Curb", "Custom", "Edge"};
  return kNames[static_cast<int>(t)];
}

const char* ToString(RoadMarkColor c) {
  static const char* kNames[] = {"Standard", "White", "Yellow", "Blue", "Green", "Red", "Orange", "Black", "Violet"};
  return kNames[static_cast<int>(c)];
}

}  // namespace lockstep::map
