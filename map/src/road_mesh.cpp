#include "lockstep/map/road_mesh.h"

#include <algorithm>
#include <cmath>

#include "lockstep/map/crossings.h"
#include "map_internal.h"

namespace lockstep::map {
namespace {

enum class Surface { Skip, Road, Sidewalk, Verge };

Surface SurfaceOf(LaneType t) {
  switch (t) {
    case LaneType::None: return Surface::Skip;
    case LaneType::Sidewalk: return Surface::Sidewalk;
    case LaneType::Border:
    case LaneType::Median: return Surface::Verge;
    default: return Surface::Road;
  }
}

bool WidthsVary(const LaneSection& sec) {
  for (const Lane& l : sec.lanes)
    for (const Poly3& w : l.widths)
      if (w.b != 0 || w.c != 0 || w.d != 0) return true;
  return false;
}

// Point at road coordinate (s, t) lifted by dz, with the reference heading.
Eigen::Vector3d At(const Road& road, double s, double t, double dz) {
  Eigen::Vector3d p = RoadToWorld(road, s, t);
  p.z() += dz;
  return p;
}

// A paint stripe of half width hw centred on the border t(s) over [s0, s1].
template <class BorderT>
void AddStripe(Mesh& m, const Road& road, double s0, double s1, BorderT border, double hw, double lift, double step) {
  const std::vector<double> st = SampleStations(road, s0, s1, step, std::min(step, 1.0));
  for (std::size_t k = 0; k + 1 < st.size(); ++k) {
    const double a = st[k], b = st[k + 1];
    if (b - a < 1e-6) continue;
    const double ta = border(a), tb = border(b);
    m.AddQuad(At(road, a, ta - hw, lift), At(road, b, tb - hw, lift), At(road, b, tb + hw, lift),
              At(road, a, ta + hw, lift), Eigen::Vector3d::UnitZ());
  }
}

// Zebra stripes of a junction-mouth crossing: bands along the road (into_junction),
// `o.junction_crosswalk_width_m` long, 0.5 m wide every 1 m across it, only where they lie
// on a driving lane; centred on the walkers' crossing line.
void AddMouthZebra(Mesh& paint, const Map& map, const MouthCrossing& c, const RoadMeshOptions& o) {
  const Eigen::Vector3d span = c.ends[1] - c.ends[0];
  const double len = span.head<2>().norm();
  if (len < 1.0 || len > 60.0) return;
  const Eigen::Vector3d across = Eigen::Vector3d(span.x(), span.y(), 0) / len;
  const Eigen::Vector3d half_band = c.into_junction * (0.5 * o.junction_crosswalk_width_m);
  const Eigen::Vector3d half_stripe = across * 0.25;
  for (double u = 0.5; u + 0.5 <= len; u += 1.0) {
    const Eigen::Vector3d mid = c.ends[0] + span * (u / len);
    if (!OnDrivingLane(map, mid) || !OnDrivingLane(map, mid - half_band) || !OnDrivingLane(map, mid + half_band)) continue;
    const Eigen::Vector3d lift(0, 0, o.marking_lift_m);
    paint.AddQuad(mid - half_band - half_stripe + lift, mid + half_band - half_stripe + lift, mid + half_band + half_stripe + lift,
                  mid - half_band + half_stripe + lift, Eigen::Vector3d::UnitZ());
  }
}

}  // namespace

std::vector<Mesh> BuildRoadMeshes(const Map& map, const RoadMeshOptions& o, std::uint32_t first_instance_id) {
  std::vector<Mesh> out;
  const OpenDrive& od = map.Data();
  double total = 0;
  for (const Road& r : od.roads) total += r.length;
  const double scale = std::max(1.0, total / 200000.0);  // bound the work on huge or hostile maps
  std::vector<LaneSpan> spans_a, spans_b;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
  std::vector<MouthCrossing> mouths;
  if (o.junction_crosswalks) mouths = JunctionMouthCrossings(map);
  for (const Road& road : od.roads) {
    Mesh surf, walk, verge, paint;
    surf.name = "road_" + road.id;
    surf.semantic_tag = semantic::kRoads;
    walk.name = "sidewalk_" + road.id;
    walk.semantic_tag = semantic::kSideWalks;
    verge.name = "verge_" + road.id;
    verge.semantic_tag = semantic::kTerrain;
    paint.name = "markings_" + road.id;
    paint.semantic_tag = semantic::kRoadLine;
    for (std::size_t si = 0; si < road.sections.size(); ++si) {
      const LaneSection& sec = road.sections[si];
      if (sec.length <= 1e-6) continue;
      const double curve = o.curve_step_m * scale;
      const double straight = (WidthsVary(sec) ? o.curve_step_m : o.straight_step_m) * scale;
      const std::vector<double> st = SampleStations(road, sec.s, sec.s + sec.length, straight, curve);
      for (std::size_t k = 0; k + 1 < st.size(); ++k) {
        const double a = st[k], b = st[k + 1];
        if (b - a < 1e-6) continue;
        LaneSpans(road, si, a, &spans_a);
        LaneSpans(road, si, b, &spans_b);
        for (std::size_t i = 0; i < sec.lanes.size(); ++i) {
          const Lane& lane = sec.lanes[i];
          if (lane.id == 0) continue;
          const Surface kind = SurfaceOf(lane.type);
          const LaneSpan& la = spans_a[i];
          const LaneSpan& lb = spans_b[i];
          if (kind == Surface::Skip || (la.Width() < 1e-3 && lb.Width() < 1e-3)) continue;
          const double dz = kind == Surface::Sidewalk ? o.curb_height_m : 0.0;
          Mesh& m = kind == Surface::Road ? surf : kind == Surface::Sidewalk ? walk : verge;
          const Eigen::Vector3d ia = At(road, a, la.t_inner, dz), ib = At(road, b, lb.t_inner, dz);
          const Eigen::Vector3d oa = At(road, a, la.t_outer, dz), ob = At(road, b, lb.t_outer, dz);
          m.AddQuad(ia, ib, ob, oa, up);
          if (kind == Surface::Sidewalk) {
            // Curb faces on both long sides, facing away from the sidewalk.
            const Eigen::Vector3d across = (oa - ia).normalized();
            const Eigen::Vector3d drop(0, 0, o.curb_height_m);
            m.AddQuad(ia - drop, ib - drop, ib, ia, -across);
            m.AddQuad(oa - drop, ob - drop, ob, oa, across);
          }
        }
      }
      // Lane markings: each lane owns the paint on its outer border, lane 0 the centre line.
      for (const Lane& lane : sec.lanes) {
        for (std::size_t mi = 0; mi < lane.marks.size(); ++mi) {
          const RoadMark& mk = lane.marks[mi];
          const RoadMarkType t = mk.type;
          if (t == RoadMarkType::None || t == RoadMarkType::Curb || t == RoadMarkType::Grass || mk.width <= 0) continue;
          const double m0 = sec.s + std::max(0.0, mk.s_offset);
          const double m1 = mi + 1 < lane.marks.size() ? sec.s + lane.marks[mi + 1].s_offset : sec.s + sec.length;
          if (m1 - m0 < 1e-3) continue;
          const int id = lane.id;
          auto border = [&](double s) {
            const LaneSpan sp = LaneSpanOf(road, si, id, s);
            return id == 0 ? sp.t_inner : sp.t_outer;
          };
          const double hw = 0.5 * mk.width;
          const bool twin = t == RoadMarkType::SolidSolid || t == RoadMarkType::SolidBroken ||
                            t == RoadMarkType::BrokenSolid || t == RoadMarkType::BrokenBroken;
          // For twin lines, which of the two stripes is dashed (first = towards +t).
          const bool dashed_a = t == RoadMarkType::Broken || t == RoadMarkType::BrokenSolid ||
                                t == RoadMarkType::BrokenBroken || t == RoadMarkType::BottsDots;
          const bool dashed_b = t == RoadMarkType::SolidBroken || t == RoadMarkType::BrokenBroken;
          const double gap = twin ? 1.5 * mk.width : 0.0;
          for (int stripe = 0; stripe < (twin ? 2 : 1); ++stripe) {
            const double shift = twin ? (stripe == 0 ? gap : -gap) : 0.0;
            auto b = [&](double s) { return border(s) + shift; };
            const bool dashed = stripe == 0 ? dashed_a : dashed_b;
            if (!dashed) {
              AddStripe(paint, road, m0, m1, b, hw, o.marking_lift_m, o.straight_step_m * scale);
            } else {
              const double period = std::max(0.5, (o.dash_length_m + o.dash_gap_m) * scale);
              for (double s = m0; s < m1; s += period)
                AddStripe(paint, road, s, std::min(m1, s + o.dash_length_m * scale), b, hw, o.marking_lift_m,
                          o.dash_length_m * scale);
            }
          }
        }
      }
    }
    // Crosswalks: zebra stripes along the road over the object's outline bounding box.
    for (const RoadObject& obj : road.objects) {
      if (obj.type != "crosswalk") continue;
      double u0 = 1e9, u1 = -1e9, v0 = 1e9, v1 = -1e9;
      for (const auto& [u, v] : obj.outline_local) {
        u0 = std::min(u0, u); u1 = std::max(u1, u); v0 = std::min(v0, v); v1 = std::max(v1, v);
      }
      if (obj.outline_local.empty()) {  // no outline: length along the road, width across
        u0 = -0.5 * obj.length; u1 = 0.5 * obj.length; v0 = -0.5 * obj.width; v1 = 0.5 * obj.width;
      }
      if (!(u1 > u0) || !(v1 > v0) || (v1 - v0) > 200 || (u1 - u0) > 200) continue;
      const double c = std::cos(obj.yaw), sn = std::sin(obj.yaw);
      auto P = [&](double u, double v) {
        return Eigen::Vector3d(obj.x + u * c - v * sn, obj.y + u * sn + v * c, obj.z + o.marking_lift_m);
      };
      for (double v = v0 + 0.25; v + 0.5 <= v1 + 1e-9; v += 1.0)
        paint.AddQuad(P(u0, v), P(u1, v), P(u1, v + 0.5), P(u0, v + 0.5), up);
    }
    for (const MouthCrossing& c : mouths) {
      if (&od.roads[static_cast<std::size_t>(c.road)] == &road) AddMouthZebra(paint, map, c, o);
    }
    for (Mesh* m : {&surf, &walk, &verge, &paint}) {
      if (m->indices.empty()) continue;
      m->instance_id = first_instance_id++;
      out.push_back(std::move(*m));
    }
  }
  return out;
}

}  // namespace lockstep::map
