#pragma once
// Ray casting with Embree 3: the static town (the map layer's meshes, the ones the
// renderer draws, with their semantic tags and instance ids) built once into its own
// BVH, plus one instance of a unit box per actor. Each frame only the actors' instance
// transforms change and the small top-level BVH is rebuilt; the town is never rebuilt.
#include <cstdint>
#include <memory>
#include <vector>

#include "lockstep/map/mesh.h"
#include "lockstep/sensors/types.h"

namespace lockstep::sensors {

struct Ray {
  float origin[3];
  float dir[3];       // unit
  float tfar;         // m
};

struct Hit {
  float distance = -1;            // m along the ray; < 0 = no hit
  float normal[3] = {0, 0, 0};    // world, unit, geometric
  uint32_t actor = 0;             // actor id when an actor was hit
  uint32_t instance_id = 0;       // static mesh instance id (map layer) when the town was hit
  uint32_t geometry = 0;          // which static mesh was hit (its index among the town's meshes, + 1); 0 = an actor
  uint8_t tag = 0;                // CARLA semantic tag
  HitKind kind = HitKind::kNone;
  bool hit() const { return distance >= 0; }
};

class RayScene {
 public:
  RayScene();
  ~RayScene();
  RayScene(const RayScene&) = delete;
  RayScene& operator=(const RayScene&) = delete;

  // Replaces the static geometry (once per map).
  void SetStatic(const std::vector<map::Mesh>& meshes);
  // The actors of a frame: instances are added, moved and removed to match `actors`;
  // only the top level is rebuilt.
  void SetActors(const std::vector<Actor>& actors);

  // Casts rays[i] into hits[i], 16 rays per Embree packet.
  void Intersect(const Ray* rays, Hit* hits, size_t n) const;
  Hit Intersect(const Ray& ray) const;
  // Like Intersect, but hits for which skip(hit) is true are passed through (the ray goes
  // on behind them): sensors that ignore their parent or static geometry.
  template <class Skip>
  Hit IntersectSkipping(Ray ray, Skip skip) const {
    float travelled = 0;
    for (int i = 0; i < 16; ++i) {
      Hit h = Intersect(ray);
      if (!h.hit()) return h;
      if (!skip(h)) {
        h.distance += travelled;
        return h;
      }
      const float step = h.distance + 1e-3f;
      for (int a = 0; a < 3; ++a) ray.origin[a] += ray.dir[a] * step;
      ray.tfar -= step;
      travelled += step;
      if (ray.tfar <= 0) return Hit{};
    }
    return Hit{};
  }

  // Every object the segment from -> to crosses, nearest first, each object once (its
  // first surface along the segment: an actor's box once, a town mesh once), as Unreal's
  // multi line traces report them (CARLA's World.cast_ray, the V2X path-loss trace).
  // Hit.distance is from `from`. At most `max_hits` objects.
  std::vector<Hit> IntersectAll(const Vec3& from, const Vec3& to, size_t max_hits = 256) const;

  size_t static_triangles() const;
  size_t actor_count() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace lockstep::sensors
