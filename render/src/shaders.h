#pragma once
// GLSL 3.30 core sources of the camera pass (scene and sky) and the shadow pass.
namespace lockstep::render::shaders {

inline constexpr const char* kCommon = R"(#version 330 core
uniform mat4 u_view_proj;
uniform mat4 u_prev_view_proj;
uniform mat4 u_view;
uniform vec3 u_camera;
uniform vec3 u_sun_dir;
uniform vec3 u_sun_color;
uniform vec3 u_ambient;
uniform vec3 u_sky_zenith;
uniform vec3 u_sky_horizon;
uniform vec3 u_fog_color;
uniform float u_fog_extinction;
uniform float u_fog_start;
uniform float u_fog_falloff;
uniform float u_rain;
uniform float u_rain_slant;
uniform float u_clouds;
uniform float u_exposure;
uniform float u_gamma;
uniform float u_vignette;
uniform float u_vignette_falloff;
uniform vec2 u_size;
uniform uint u_seed;
uniform bool u_post;

uint Hash(uint x) {
  x ^= x >> 16; x *= 0x7feb352du; x ^= x >> 15; x *= 0x846ca68bu; x ^= x >> 16;
  return x;
}
float Hash2(vec2 p) {
  return float(Hash(floatBitsToUint(p.x) ^ Hash(floatBitsToUint(p.y) + 0x9e3779b9u))) / 4294967295.0;
}
// Value noise with smoothstep between lattice points. The lattice values are a 256 x 256
// texture (repeating): one bilinear fetch at the smoothstepped position costs llvmpipe
// far less than hashing four corners.
uniform sampler2D u_noise;
float Noise(vec2 p) {
  vec2 i = floor(p), f = fract(p);
  vec2 u = f * f * (3.0 - 2.0 * f);
  return texture(u_noise, (i + u + 0.5) * (1.0 / 256.0)).r;
}
vec3 SkyColor(vec3 dir) {
  float h = clamp(dir.z, -0.2, 1.0);
  vec3 c = mix(u_sky_horizon, u_sky_zenith, pow(max(h, 0.0), 0.6));
  if (h < 0.0) c = u_sky_horizon * 0.8;
  // Sun disc and glow: sd^900 and sd^12 by squaring (llvmpipe's pow is a log and an exp).
  float s1 = max(dot(dir, u_sun_dir), 0.0);
  float s2 = s1 * s1, s4 = s2 * s2, s12 = s4 * s4 * s4;
  float s60 = s12 * s12 * s12 * s12 * s12;
  float s300 = s60 * s60 * s60 * s60 * s60;
  float s900 = s300 * s300 * s300;
  c += u_sun_color * (s900 * 6.0 + s12 * 0.12);
#ifdef FEATURE_CLOUDS
  if (dir.z > 0.01) {
    vec2 uv = dir.xy / dir.z * 2.0;
    float n = Noise(uv) * 0.65 + Noise(uv * 2.7) * 0.35;
    float cover = smoothstep(1.0 - u_clouds, 1.0 - u_clouds + 0.25, n);
    vec3 cloud = (u_ambient * 1.6 + u_sun_color * 0.25) * (1.0 - 0.5 * u_rain);
    c = mix(c, cloud, cover * smoothstep(0.01, 0.15, dir.z));
  }
#endif
  return c;
}
vec3 Fog(vec3 color, vec3 world) {
  float d = length(world - u_camera);
  float h = max(0.0, 0.5 * (world.z + u_camera.z));
  float ext = u_fog_extinction * exp(-u_fog_falloff * h);
  float f = 1.0 - exp(-ext * max(0.0, d - u_fog_start));
  return mix(color, u_fog_color, clamp(f, 0.0, 1.0));
}
vec3 Finish(vec3 c, vec2 frag) {
#ifdef FEATURE_RAIN
  if (u_post) {
    // Rain streaks: thin slanted lines, a fixed pattern per frame seed.
    vec2 p = vec2(frag.x + frag.y * u_rain_slant, frag.y);
    vec2 cell = vec2(floor(p.x / 3.0), floor(p.y / 40.0 + Hash2(vec2(floor(p.x / 3.0), float(u_seed & 1023u)))));
    float r = Hash2(cell + vec2(float(u_seed >> 10), 7.0));
    float streak = step(1.0 - 0.12 * u_rain, r) * step(abs(fract(p.x / 3.0) - 0.5), 0.2);
    c = mix(c, vec3(0.75, 0.78, 0.82) * (0.3 + u_ambient.g * 2.0), streak * 0.45);
  }
#endif
  c *= u_exposure;
  c = vec3(1.0) - exp(-c);
#ifdef FEATURE_VIGNETTE
  vec2 q = (frag / u_size - 0.5) * 2.0;
  c *= clamp(1.0 - u_vignette * pow(length(q) / 1.4142, u_vignette_falloff), 0.0, 1.0);
#endif
  c = clamp(c, 0.0, 1.0);
#ifdef GAMMA_22
  // c^(1/2.2) as a polynomial in sqrt(c), within 0.64/255 (llvmpipe's pow is a log and an exp).
  vec3 s = sqrt(c);
  return s * (1.32276594 + s * (-0.97385348 + s * (1.14817012 - 0.49958284 * s)));
#else
  return pow(c, vec3(1.0 / u_gamma));
#endif
}
)";

inline constexpr const char* kSceneVertex = R"(
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;
layout(location = 3) in uint a_label;
uniform mat4 u_model;
uniform mat4 u_prev_model;
uniform vec3 u_paint;
// The same position in every variant: the colour pass after a depth pre-pass tests
// against the pre-pass's depth.
invariant gl_Position;
out vec3 v_world;
// Normals are per face (models and town are flat-shaded): one per triangle, not interpolated.
flat out vec3 v_normal;
flat out vec2 v_wall;  // horizontal direction along a wall (building windows)
flat out vec3 v_albedo;
flat out uint v_label;
flat out uint v_material;
#ifdef OUT_FLOW
out vec4 v_prev_clip;  // the current position is the pixel's own (gl_FragCoord)
#endif
out float v_depth;
void main() {
  vec4 w = u_model * vec4(a_pos, 1.0);
  v_world = w.xyz;
  v_normal = normalize(mat3(u_model) * a_normal);
  v_wall = normalize(vec2(-v_normal.y, v_normal.x) + vec2(1e-9, 0.0));
  v_label = a_label;
  v_material = uint(a_color.a * 255.0 + 0.5);
  // Linear albedo per vertex (flat): the fragment shader has no gamma to undo.
  v_albedo = pow(v_material == 1u ? u_paint : a_color.rgb, vec3(2.2));
  v_depth = -(u_view * w).z;
  gl_Position = u_view_proj * w;
#ifdef OUT_FLOW
  v_prev_clip = u_prev_view_proj * (u_prev_model * vec4(a_pos, 1.0));
#endif
}
)";

// Weather features are compiled in only where the weather has them (FEATURE_* defines):
// llvmpipe runs both sides of every branch, so unused code would cost every pixel.
inline constexpr const char* kSceneFragment = R"(
in vec3 v_world;
flat in vec3 v_normal;
flat in vec2 v_wall;
flat in vec3 v_albedo;
flat in uint v_label;
flat in uint v_material;
#ifdef OUT_FLOW
in vec4 v_prev_clip;
#endif
in float v_depth;
uniform uint u_instance;
uniform int u_lights;         // vehicle: carla.VehicleLightState bits
uniform int u_light_state;   // traffic light: 0 red, 1 yellow, 2 green, 3 off
uniform float u_wetness;
uniform float u_puddles;
uniform int u_lamp_count;
uniform vec3 u_lamps[16];
uniform int u_spot_count;
uniform vec3 u_spot_pos[16];
uniform vec3 u_spot_dir[16];
uniform sampler2DShadow u_shadow_map;
uniform mat4 u_shadow_matrix;
layout(location = 0) out vec4 o_color;
layout(location = 1) out uvec4 o_label;
layout(location = 2) out float o_depth;
layout(location = 3) out vec4 o_normal;
layout(location = 4) out vec2 o_flow;

void main() {
  vec3 n = v_normal;
  if (!gl_FrontFacing) n = -n;
  uint tag = v_label & 255u;
  uint inst = v_label >> 8;
  if (inst == 0u) inst = u_instance;
  o_label = uvec4(tag, inst & 255u, (inst >> 8) & 255u, (inst >> 16) & 255u);
  o_depth = v_depth;
  // Normals and flow only in the variants that output them (OUT_* defines).
#ifdef OUT_NORMALS
  vec3 en = normalize(mat3(u_view) * n);
  o_normal = vec4(en.zyx * 0.5 + 0.5, 1.0);  // stored B, G, R, A: R = x (read back as bytes)
#else
  o_normal = vec4(0.0);
#endif
#ifdef OUT_FLOW
  // The pixel centre in NDC (rows are flipped by the projection, so y up in NDC is y up
  // in the framebuffer): four interpolated floats fewer than the clip position.
  vec2 ndc = gl_FragCoord.xy / u_size * 2.0 - 1.0, prev = v_prev_clip.xy / v_prev_clip.w;
  o_flow = ndc - prev;
#else
  o_flow = vec2(0.0);
#endif
#ifndef LOCKSTEP_COLOR
  o_color = vec4(0.0);  // a pass without colour output skips the lighting
#else
  vec3 albedo = v_albedo;
  uint mat = v_material;
  vec3 view = normalize(u_camera - v_world);
  float spec = mat == 2u ? 0.6 : (mat == 1u ? 0.25 : 0.0);
  vec3 emissive = vec3(0.0);
#ifdef FEATURE_WET
  if (n.z > 0.7 && tag != 9u) {
    albedo *= 1.0 - 0.45 * u_wetness;
    spec += 0.5 * u_wetness;
  }
#endif
  if (mat == 10u && abs(n.z) < 0.5) {
    // Building windows: a grid on the walls, some lit at night.
    float along = dot(v_world.xy, gl_FrontFacing ? v_wall : -v_wall);
    vec2 cell = vec2(along / 2.6, (v_world.z + 0.2) / 3.2);
    vec2 f = fract(cell);
    if (f.x > 0.25 && f.x < 0.75 && f.y > 0.3 && f.y < 0.8) {
      albedo = vec3(0.03, 0.04, 0.05);
      spec = 0.5;
#ifdef FEATURE_NIGHT
      if (Hash2(floor(cell)) > 0.55) emissive = vec3(1.0, 0.75, 0.4) * 0.9;
#endif
    }
  }
  // Vehicle lamps by carla.VehicleLightState bits: head lamps with the low or high beam
  // (dim with the position lights alone), tail lamps bright with the brake, dim with the
  // position lights or beams.
  if (mat == 3u) {
    if ((u_lights & 6) != 0) emissive = vec3(6.0, 5.6, 4.5) * ((u_lights & 4) != 0 ? 1.4 : 1.0);
    else if ((u_lights & 1) != 0) emissive = vec3(1.2, 1.1, 0.9);
  }
  if (mat == 4u) {
    if ((u_lights & 8) != 0) emissive = vec3(6.0, 0.15, 0.15);
    else if ((u_lights & 7) != 0) emissive = vec3(2.0, 0.07, 0.07);
  }
#ifdef FEATURE_NIGHT
  if (mat == 6u) emissive = vec3(8.0, 6.5, 4.0);
#endif
  if (mat >= 7u && mat <= 9u) {
    int lamp = int(mat) - 7;
    vec3 c = lamp == 0 ? vec3(1.0, 0.05, 0.02) : (lamp == 1 ? vec3(1.0, 0.6, 0.0) : vec3(0.1, 1.0, 0.3));
    albedo = c * 0.08;
    if (lamp == u_light_state) emissive = c * 5.0;
  }
  float ndl = max(dot(n, u_sun_dir), 0.0);
#ifdef FEATURE_SHADOWS
  vec4 sc = u_shadow_matrix * vec4(v_world + n * 0.05, 1.0);
  vec3 sp = sc.xyz * 0.5 + 0.5;
  float lit = ndl > 0.0 && all(greaterThan(sp.xy, vec2(0.0))) && all(lessThan(sp.xy, vec2(1.0)))
                  ? texture(u_shadow_map, vec3(sp.xy, sp.z - 0.0015)) : 1.0;
#else
  float lit = 1.0;
#endif
  vec3 light = u_ambient * (0.75 + 0.25 * n.z) + u_sun_color * (ndl * lit);
#ifdef FEATURE_NIGHT
  for (int i = 0; i < u_lamp_count; ++i) {
    vec3 l = u_lamps[i] - v_world;
    float d2 = dot(l, l);
    light += vec3(1.0, 0.8, 0.55) * (40.0 / (1.0 + d2)) * max(dot(n, l * inversesqrt(d2)), 0.0);
  }
  for (int i = 0; i < u_spot_count; ++i) {
    vec3 l = u_spot_pos[i] - v_world;
    float d2 = dot(l, l);
    vec3 ld = l * inversesqrt(d2);
    float cone = smoothstep(0.82, 0.95, dot(-ld, u_spot_dir[i]));
    light += vec3(1.0, 0.95, 0.85) * (90.0 / (1.0 + d2)) * cone * max(dot(n, ld), 0.0);
  }
#endif
  vec3 color = albedo * light + emissive;
  vec3 h = normalize(u_sun_dir + view);
  // Blinn-Phong exponent 40 by squaring: x^40 = x^32 x^8 (llvmpipe's pow is a log and an exp).
  float nh = max(dot(n, h), 0.0);
  float nh2 = nh * nh, nh4 = nh2 * nh2, nh8 = nh4 * nh4, nh16 = nh8 * nh8;
  color += u_sun_color * (spec * lit) * (nh16 * nh16 * nh8);
#ifdef FEATURE_PUDDLES
  if (mat == 5u && n.z > 0.7) {
    float nz = Noise(v_world.xy * 0.35) * 0.7 + Noise(v_world.xy * 1.3) * 0.3;
    float puddle = smoothstep(1.0 - 0.55 * u_puddles, 1.0 - 0.55 * u_puddles + 0.05, nz);
    vec3 r = reflect(-view, vec3(0, 0, 1));
    color = mix(color, mix(u_sky_horizon, u_sky_zenith, clamp(r.z, 0.0, 1.0)) * 0.8, 0.75 * puddle);
  }
#endif
  color = Fog(color, v_world);
  o_color = vec4(Finish(color, gl_FragCoord.xy).bgr, 1.0);  // stored B, G, R, A: read back as bytes
#endif
}
)";

// Sky: a full-screen triangle at the far plane, drawn where nothing else was.
inline constexpr const char* kSkyVertex = R"(
out vec2 v_ndc;
void main() {
  vec2 p = vec2((gl_VertexID == 1) ? 3.0 : -1.0, (gl_VertexID == 2) ? 3.0 : -1.0);
  v_ndc = p;
  gl_Position = vec4(p, 1.0, 1.0);
}
)";

inline constexpr const char* kSkyFragment = R"(
in vec2 v_ndc;
uniform mat4 u_inv_view_proj_rot;   // clip to world direction (camera rotation only)
uniform mat4 u_prev_view_proj_rot;  // world direction to the previous clip (rotation only)
layout(location = 0) out vec4 o_color;
layout(location = 1) out uvec4 o_label;
layout(location = 2) out float o_depth;
layout(location = 3) out vec4 o_normal;
layout(location = 4) out vec2 o_flow;
void main() {
  vec4 w = u_inv_view_proj_rot * vec4(v_ndc, 1.0, 1.0);
  vec3 dir = normalize(w.xyz / w.w);
  o_label = uvec4(11u, 0u, 0u, 0u);
  o_depth = 1000.0;
  o_normal = vec4(0.0);
#ifdef OUT_FLOW
  vec4 prev = u_prev_view_proj_rot * vec4(dir, 0.0);
  o_flow = prev.w > 0.0 ? v_ndc - prev.xy / prev.w : vec2(0.0);
#else
  o_flow = vec2(0.0);
#endif
#ifndef LOCKSTEP_COLOR
  o_color = vec4(0.0);
#else
  vec3 c = SkyColor(dir);
  c = mix(c, u_fog_color, clamp(u_fog_extinction * 60.0, 0.0, 1.0));
  o_color = vec4(Finish(c, gl_FragCoord.xy).bgr, 1.0);
#endif
}
)";

// world.debug shapes (debug_draw.h): unlit triangles in their own colour, depth-tested
// against the scene, into the colour output only.
inline constexpr const char* kDebugVertex = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
layout(location = 1) in vec4 a_color;
uniform mat4 u_view_proj;
out vec4 v_color;
void main() {
  v_color = a_color;
  gl_Position = u_view_proj * vec4(a_pos, 1.0);
}
)";

inline constexpr const char* kDebugFragment = R"(#version 330 core
in vec4 v_color;
layout(location = 0) out vec4 o_color;
void main() { o_color = vec4(v_color.bgr, 1.0); }  // stored B, G, R, A as the scene's
)";

inline constexpr const char* kShadowVertex = R"(#version 330 core
layout(location = 0) in vec3 a_pos;
uniform mat4 u_light_view_proj;
uniform mat4 u_model;
void main() { gl_Position = u_light_view_proj * (u_model * vec4(a_pos, 1.0)); }
)";
inline constexpr const char* kShadowFragment = R"(#version 330 core
void main() {}
)";

}  // namespace lockstep::render::shaders
