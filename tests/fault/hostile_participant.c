/* lockstep_hostile_participant: a foreign DDS participant (C11 on Cyclone DDS, not
 * Lockstep's own code path) that publishes malformed and extreme samples on every command,
 * membership, clock and state topic of a running simulation (issue 21, item 6):
 * NaN and infinities, values far out of the world, sequences at their bounds and unbounded
 * ones of 2000 elements (20 times a town's),
 * unknown actor ids, unknown enum values, frames from the past and the future, another
 * run's id, and a duplicate of a live service's name.
 *
 * It waits until the run is RUNNING at frame >= --after and lists a vehicle and a drone
 * (lockstep/actors), then sends every command of its list once (client "hostile"), then the
 * samples on the other topics, and waits up to --timeout s for every command's reply.
 * Output (stdout), one line each:
 *   target run=<r> frame=<f> vehicle=<id> drone=<id> service=<name>
 *   sent <seq> <label>
 *   published <topic> <label>
 *   reply <seq> accepted=<0|1> reason=<text>   (labels "[service] ...": the coordinator
 *                                   passes it, the owning service refuses it in its log)
 *   missing <seq> <label>          (no reply within the timeout)
 *   finished sent=<n> replies=<n>
 * Exit 0 when it ran its list (whatever the replies), 2 on a DDS error or no target.
 * Network settings: CYCLONEDDS_URI (client/cyclone_c/README.md). */
#define _POSIX_C_SOURCE 200809L

#include <inttypes.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "dds/dds.h"
#include "lockstep/actors.h"
#include "lockstep/blueprint.h"
#include "lockstep/clock.h"
#include "lockstep/command.h"
#include "lockstep/state.h"

#define MAX_COMMANDS 128
#define CLIENT "hostile"

static void die(const char *what, dds_return_t rc) {
  fprintf(stderr, "lockstep_hostile_participant: %s: %s\n", what, dds_strretcode(rc));
  exit(2);
}

static dds_entity_t check(dds_entity_t e, const char *what) {
  if (e < 0) die(what, e);
  return e;
}

static dds_qos_t *family_qos(bool transient_local, int32_t depth) {
  dds_qos_t *q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_liveliness(q, DDS_LIVELINESS_AUTOMATIC, DDS_INFINITY);
  dds_qset_destination_order(q, DDS_DESTINATIONORDER_BY_RECEPTION_TIMESTAMP);
  dds_qset_ownership(q, DDS_OWNERSHIP_SHARED);
  return q;
}

static dds_entity_t g_dp;

static dds_entity_t reader(const dds_topic_descriptor_t *desc, const char *name, bool tl, int32_t depth) {
  dds_qos_t *q = family_qos(tl, depth);
  dds_entity_t t = check(dds_create_topic(g_dp, desc, name, NULL, NULL), name);
  dds_entity_t r = check(dds_create_reader(g_dp, t, q, NULL), name);
  dds_delete_qos(q);
  return r;
}

static dds_entity_t writer(const dds_topic_descriptor_t *desc, const char *name, bool tl, int32_t depth) {
  dds_qos_t *q = family_qos(tl, depth);
  dds_entity_t t = check(dds_create_topic(g_dp, desc, name, NULL, NULL), name);
  dds_entity_t w = check(dds_create_writer(g_dp, t, q, NULL), name);
  dds_delete_qos(q);
  return w;
}

/* Waits until `w` matched at least one reader (a VOLATILE sample written before is lost). */
static bool wait_matched(dds_entity_t w, dds_duration_t timeout) {
  const dds_time_t end = dds_time() + timeout;
  while (dds_time() < end) {
    dds_publication_matched_status_t st;
    if (dds_get_publication_matched_status(w, &st) == 0 && st.current_count > 0) return true;
    dds_sleepfor(DDS_MSECS(20));
  }
  return false;
}

typedef struct target {
  uint32_t run;
  uint64_t frame;
  uint32_t vehicle, drone;
  char service[65]; /* a live required service, for the duplicate-name and ack samples */
} target;

static bool read_status(dds_entity_t status_reader, target *t, uint64_t after) {
  void *samples[1] = {NULL};
  dds_sample_info_t info[1];
  bool ok = false;
  const int32_t n = dds_read(status_reader, samples, info, 1, 1);
  if (n > 0 && info[0].valid_data) {
    const lockstep_msg_RunStatus *s = samples[0];
    t->run = s->run;
    t->frame = s->frame;
    ok = s->state == lockstep_msg_RUN_RUNNING && s->frame >= after;
    for (uint32_t i = 0; i < s->members._length; ++i) {
      const lockstep_msg_MemberStatus *m = &s->members._buffer[i];
      if (m->required && m->alive && strcmp(m->kind, "recorder") != 0) snprintf(t->service, sizeof t->service, "%s", m->service);
    }
  }
  if (n > 0) dds_return_loan(status_reader, samples, n);
  return ok && t->service[0] != 0;
}

static void read_actors(dds_entity_t actors_reader, target *t) {
  void *samples[1] = {NULL};
  dds_sample_info_t info[1];
  const int32_t n = dds_read(actors_reader, samples, info, 1, 1);
  if (n > 0 && info[0].valid_data) {
    const lockstep_msg_ActorList *l = samples[0];
    for (uint32_t i = 0; i < l->actors._length; ++i) {
      const lockstep_msg_SpawnActor *s = &l->actors._buffer[i].spawn;
      if (strncmp(s->blueprint, "vehicle.", 8) == 0 && t->vehicle == 0) t->vehicle = s->actor;
      if (strncmp(s->blueprint, "drone.", 6) == 0 && t->drone == 0) t->drone = s->actor;
    }
  }
  if (n > 0) dds_return_loan(actors_reader, samples, n);
}

/* ---- the command list ---- */

typedef struct sent_command {
  uint64_t seq;
  char label[96];
  bool replied;
} sent_command;

static sent_command g_sent[MAX_COMMANDS];
static int g_n_sent;
static dds_entity_t g_command_writer;
static char g_empty[1] = "";

static lockstep_msg_Command *fresh(lockstep_msg_CommandKind kind) {
  static lockstep_msg_Command c;
  memset(&c, 0, sizeof c);
  snprintf(c.client, sizeof c.client, "%s", CLIENT);
  c.body._d = kind;
  return &c;
}

static void send_cmd(lockstep_msg_Command *c, const char *label) {
  if (g_n_sent == MAX_COMMANDS) die("too many commands", DDS_RETCODE_OUT_OF_RESOURCES);
  if (c->body._d == lockstep_msg_CMD_LOAD_MAP) {
    if (!c->body._u.load_map.opendrive) c->body._u.load_map.opendrive = g_empty;
    if (!c->body._u.load_map.scene) c->body._u.load_map.scene = g_empty;
  }
  c->sequence_number = (uint64_t)g_n_sent + 1;
  sent_command *s = &g_sent[g_n_sent++];
  s->seq = c->sequence_number;
  snprintf(s->label, sizeof s->label, "%s", label);
  const dds_return_t rc = dds_write(g_command_writer, c);
  if (rc < 0) {
    printf("unsent %" PRIu64 " %s: %s\n", s->seq, label, dds_strretcode(rc));
    s->replied = true; /* nothing to wait for */
  } else {
    printf("sent %" PRIu64 " %s\n", s->seq, label);
  }
  fflush(stdout);
}

static lockstep_msg_Pose unit_pose(double x, double y, double z) {
  lockstep_msg_Pose p;
  memset(&p, 0, sizeof p);
  p.position.x = x;
  p.position.y = y;
  p.position.z = z;
  p.orientation.w = 1;
  return p;
}

static void send_commands(const target *t) {
  const double nan = NAN, inf = INFINITY;
  lockstep_msg_Command *c;
  static lockstep_msg_Vector3 path[1024];
  static double values[16];
  static lockstep_msg_DebugShape shapes[4096];
  static lockstep_msg_BlueprintAttribute attrs[64];

  /* spawn */
  c = fresh(lockstep_msg_CMD_SPAWN_ACTOR);
  snprintf(c->body._u.spawn_actor.blueprint, 129, "drone.generic_quad");
  c->body._u.spawn_actor.transform = unit_pose(nan, 0, 0);
  send_cmd(c, "spawn with a NaN position");
  c = fresh(lockstep_msg_CMD_SPAWN_ACTOR);
  snprintf(c->body._u.spawn_actor.blueprint, 129, "drone.generic_quad");
  c->body._u.spawn_actor.transform = unit_pose(0, 0, 0);
  c->body._u.spawn_actor.transform.orientation.z = inf;
  send_cmd(c, "spawn with an infinite orientation");
  c = fresh(lockstep_msg_CMD_SPAWN_ACTOR);
  snprintf(c->body._u.spawn_actor.blueprint, 129, "drone.generic_quad");
  c->body._u.spawn_actor.transform = unit_pose(1e300, -1e300, 1e300);
  c->body._u.spawn_actor.transform.orientation.w = 0;
  send_cmd(c, "spawn with a zero quaternion at 1e300");
  c = fresh(lockstep_msg_CMD_SPAWN_ACTOR);
  snprintf(c->body._u.spawn_actor.blueprint, 129, "vehicle.hostile.unknown");
  c->body._u.spawn_actor.transform = unit_pose(0, 0, 0);
  send_cmd(c, "spawn of an unknown blueprint");
  c = fresh(lockstep_msg_CMD_SPAWN_ACTOR);
  snprintf(c->body._u.spawn_actor.blueprint, 129, "drone.generic_quad");
  c->body._u.spawn_actor.transform = unit_pose(0, 0, 0);
  c->body._u.spawn_actor.parent = 4000000000u;
  send_cmd(c, "spawn attached to an unknown parent");
  c = fresh(lockstep_msg_CMD_SPAWN_ACTOR);
  snprintf(c->body._u.spawn_actor.blueprint, 129, "drone.generic_quad");
  c->body._u.spawn_actor.transform = unit_pose(0, 0, 0);
  snprintf(c->body._u.spawn_actor.owner, 65, "intruder");
  send_cmd(c, "spawn owned by a service that does not declare it");
  c = fresh(lockstep_msg_CMD_SPAWN_ACTOR);
  snprintf(c->body._u.spawn_actor.blueprint, 129, "drone.generic_quad");
  c->body._u.spawn_actor.transform = unit_pose(0, 0, 0);
  for (int i = 0; i < 64; ++i) {
    snprintf(attrs[i].key, sizeof attrs[i].key, "hostile_%02d_%040d", i, 0);
    memset(attrs[i].value, 'x', 256);
    attrs[i].value[256] = 0;
  }
  c->body._u.spawn_actor.attributes._length = c->body._u.spawn_actor.attributes._maximum = 64;
  c->body._u.spawn_actor.attributes._buffer = attrs;
  send_cmd(c, "spawn with 64 unknown attributes of 256 characters");

  /* actors that do not exist, actors of the wrong kind */
  c = fresh(lockstep_msg_CMD_DESTROY_ACTOR);
  c->body._u.destroy_actor.actor = 999999;
  send_cmd(c, "destroy an unknown actor");
  c = fresh(lockstep_msg_CMD_DESTROY_ACTOR);
  c->body._u.destroy_actor.actor = 0;
  send_cmd(c, "destroy actor 0");
  c = fresh(lockstep_msg_CMD_SET_TRANSFORM);
  c->body._u.set_transform.actor = t->vehicle;
  c->body._u.set_transform.transform = unit_pose(0, inf, 0);
  send_cmd(c, "set_transform to infinity");
  c = fresh(lockstep_msg_CMD_SET_TRANSFORM);
  c->body._u.set_transform.actor = t->vehicle;
  c->body._u.set_transform.transform = unit_pose(1e300, 0, 0);
  send_cmd(c, "set_transform to x = 1e300");
  c = fresh(lockstep_msg_CMD_SPAWN_ACTOR);
  snprintf(c->body._u.spawn_actor.blueprint, 129, "vehicle.tesla.model3");
  c->body._u.spawn_actor.transform = unit_pose(0, -3e9, 0.5);
  send_cmd(c, "spawn a vehicle at y = -3e9");
  c = fresh(lockstep_msg_CMD_SET_TRANSFORM);
  c->body._u.set_transform.actor = t->drone;
  c->body._u.set_transform.transform = unit_pose(0, 0, 0);
  c->body._u.set_transform.transform.orientation.w = nan;
  send_cmd(c, "set_transform with a NaN quaternion");
  c = fresh(lockstep_msg_CMD_VEHICLE_CONTROL);
  c->body._u.vehicle_control.actor = t->vehicle;
  c->body._u.vehicle_control.throttle = (float)nan;
  send_cmd(c, "vehicle_control with a NaN throttle");
  c = fresh(lockstep_msg_CMD_VEHICLE_CONTROL);
  c->body._u.vehicle_control.actor = t->vehicle;
  c->body._u.vehicle_control.steer = (float)-inf;
  send_cmd(c, "vehicle_control with an infinite steer");
  c = fresh(lockstep_msg_CMD_VEHICLE_CONTROL);
  c->body._u.vehicle_control.actor = t->drone;
  c->body._u.vehicle_control.throttle = 0.5f;
  send_cmd(c, "vehicle_control of a drone");
  c = fresh(lockstep_msg_CMD_VEHICLE_CONTROL);
  c->body._u.vehicle_control.actor = t->vehicle;
  c->body._u.vehicle_control.gear = INT32_MIN;
  c->body._u.vehicle_control.manual_gear_shift = true;
  send_cmd(c, "vehicle_control with gear INT32_MIN");
  c = fresh(lockstep_msg_CMD_WALKER_CONTROL);
  c->body._u.walker_control.actor = t->vehicle;
  c->body._u.walker_control.direction.x = inf;
  send_cmd(c, "walker_control with an infinite direction");
  c = fresh(lockstep_msg_CMD_WALKER_CONTROL);
  c->body._u.walker_control.actor = 123456;
  c->body._u.walker_control.speed = 1;
  send_cmd(c, "walker_control of an unknown actor");

  /* drones */
  c = fresh(lockstep_msg_CMD_DRONE);
  c->body._u.drone.actor = t->drone;
  c->body._u.drone.kind = lockstep_msg_DRONE_MOVE_TO_POSITION;
  c->body._u.drone.target.z = nan;
  c->body._u.drone.velocity = 1;
  send_cmd(c, "drone move_to_position with a NaN target");
  c = fresh(lockstep_msg_CMD_DRONE);
  c->body._u.drone.actor = t->drone;
  c->body._u.drone.kind = lockstep_msg_DRONE_MOVE_ON_PATH;
  for (int i = 0; i < 1024; ++i) {
    path[i].x = i;
    path[i].y = -i;
    path[i].z = 5;
  }
  path[1023].z = nan;
  c->body._u.drone.path._length = c->body._u.drone.path._maximum = 1024;
  c->body._u.drone.path._buffer = path;
  c->body._u.drone.velocity = 3;
  send_cmd(c, "drone move_on_path of 1024 points, the last NaN");
  c = fresh(lockstep_msg_CMD_DRONE);
  c->body._u.drone.actor = t->drone;
  c->body._u.drone.kind = lockstep_msg_DRONE_MOVE_TO_POSITION;
  c->body._u.drone.target.x = 1e300;
  c->body._u.drone.velocity = 5;
  send_cmd(c, "drone move_to_position to x = 1e300");
  c = fresh(lockstep_msg_CMD_DRONE);
  c->body._u.drone.actor = t->drone;
  c->body._u.drone.kind = lockstep_msg_DRONE_MOVE_TO_POSITION;
  c->body._u.drone.velocity = inf;
  send_cmd(c, "drone move_to_position at infinite velocity");
  c = fresh(lockstep_msg_CMD_DRONE);
  c->body._u.drone.actor = t->drone;
  c->body._u.drone.kind = lockstep_msg_DRONE_MOVE_BY_MOTOR_PWMS;
  for (int i = 0; i < 16; ++i) values[i] = 0.5;
  c->body._u.drone.values._length = c->body._u.drone.values._maximum = 16;
  c->body._u.drone.values._buffer = values;
  send_cmd(c, "drone motor PWMs with 16 values");
  c = fresh(lockstep_msg_CMD_DRONE);
  c->body._u.drone.actor = t->drone;
  c->body._u.drone.kind = lockstep_msg_DRONE_SET_KINEMATICS;
  values[0] = nan;
  c->body._u.drone.values._length = c->body._u.drone.values._maximum = 4;
  c->body._u.drone.values._buffer = values;
  send_cmd(c, "drone set_kinematics with a NaN orientation");
  c = fresh(lockstep_msg_CMD_DRONE);
  c->body._u.drone.actor = t->drone;
  c->body._u.drone.kind = lockstep_msg_DRONE_SET_GAINS;
  c->body._u.drone.gains.kd.y = -inf;
  send_cmd(c, "drone set_gains with an infinite gain");
  c = fresh(lockstep_msg_CMD_DRONE);
  c->body._u.drone.actor = t->vehicle;
  c->body._u.drone.kind = lockstep_msg_DRONE_ARM;
  send_cmd(c, "drone arm of a vehicle");

  /* traffic */
  c = fresh(lockstep_msg_CMD_TRAFFIC_LIGHT);
  c->body._u.traffic_light.actor = 777777;
  c->body._u.traffic_light.action = lockstep_msg_LIGHT_SET;
  send_cmd(c, "traffic light of an unknown actor");
  c = fresh(lockstep_msg_CMD_TRAFFIC_MANAGER);
  c->body._u.traffic_manager.parameter = lockstep_msg_TM_AUTOPILOT;
  c->body._u.traffic_manager.actor = t->vehicle;
  c->body._u.traffic_manager.value = nan;
  send_cmd(c, "traffic manager autopilot NaN");
  c = fresh(lockstep_msg_CMD_TRAFFIC_MANAGER);
  c->body._u.traffic_manager.parameter = lockstep_msg_TM_SET_PATH;
  c->body._u.traffic_manager.actor = t->vehicle;
  for (int i = 0; i < 256; ++i) path[i].z = 0;
  path[255].x = -inf;
  c->body._u.traffic_manager.path._length = c->body._u.traffic_manager.path._maximum = 256;
  c->body._u.traffic_manager.path._buffer = path;
  send_cmd(c, "traffic manager set_path of 256 points, the last infinite");
  c = fresh(lockstep_msg_CMD_TRAFFIC_MANAGER);
  c->body._u.traffic_manager.parameter = lockstep_msg_TM_DISTANCE_TO_LEADING_VEHICLE;
  c->body._u.traffic_manager.value = 1e308;
  send_cmd(c, "traffic manager distance 1e308");

  /* world */
  c = fresh(lockstep_msg_CMD_SET_WEATHER);
  c->body._u.weather.cloudiness = (float)nan;
  send_cmd(c, "weather with a NaN cloudiness");
  c = fresh(lockstep_msg_CMD_SET_WEATHER);
  c->body._u.weather.fog_distance = (float)inf;
  send_cmd(c, "weather with an infinite fog distance");
  c = fresh(lockstep_msg_CMD_SET_WORLD_SETTINGS);
  c->body._u.world_settings.fixed_delta_seconds = nan;
  send_cmd(c, "world settings with a NaN step");
  c = fresh(lockstep_msg_CMD_SET_WORLD_SETTINGS);
  c->body._u.world_settings.fixed_delta_seconds = 0.05;
  c->body._u.world_settings.real_time_factor = -inf;
  send_cmd(c, "world settings with a real-time factor of -infinity");
  c = fresh(lockstep_msg_CMD_LOAD_MAP);
  send_cmd(c, "load_map without a name or text");
  c = fresh(lockstep_msg_CMD_LOAD_MAP);
  {
    static char garbage[200001];
    memset(garbage, 'A', sizeof garbage - 1);
    garbage[sizeof garbage - 1] = 0;
    c->body._u.load_map.opendrive = garbage;
    send_cmd(c, "load_map of 200 kB that is not OpenDRIVE");
  }
  c = fresh(lockstep_msg_CMD_TICK);
  c->body._u.tick_request.count = 5;
  send_cmd(c, "tick request in free-running mode");
  c = fresh(lockstep_msg_CMD_TICK);
  c->body._u.tick_request.count = 4000000000u;
  send_cmd(c, "tick request of 4e9 ticks");

  /* ground_sim's commands */
  c = fresh(lockstep_msg_CMD_VEHICLE_ACKERMANN);
  c->body._u.ackermann.actor = t->vehicle;
  c->body._u.ackermann.speed = (float)nan;
  send_cmd(c, "ackermann with a NaN speed");
  c = fresh(lockstep_msg_CMD_ACTOR_PHYSICS);
  c->body._u.actor_physics.actor = t->vehicle;
  c->body._u.actor_physics.kind = lockstep_msg_PHYSICS_ADD_IMPULSE;
  c->body._u.actor_physics.value.y = nan;
  send_cmd(c, "add_impulse NaN");
  c = fresh(lockstep_msg_CMD_ACTOR_PHYSICS);
  c->body._u.actor_physics.actor = t->vehicle;
  c->body._u.actor_physics.kind = lockstep_msg_PHYSICS_SET_TARGET_VELOCITY;
  c->body._u.actor_physics.value.x = 1e300;
  send_cmd(c, "set_target_velocity 1e300 m/s");
  c = fresh(lockstep_msg_CMD_ACTOR_PHYSICS);
  c->body._u.actor_physics.actor = t->vehicle;
  c->body._u.actor_physics.kind = lockstep_msg_PHYSICS_ADD_IMPULSE;
  c->body._u.actor_physics.value.z = -1e200;
  send_cmd(c, "add_impulse of 1e200 N s");
  c = fresh(lockstep_msg_CMD_ACTOR_PHYSICS);
  c->body._u.actor_physics.actor = t->drone;
  c->body._u.actor_physics.kind = lockstep_msg_PHYSICS_SET_TARGET_ANGULAR_VELOCITY;
  c->body._u.actor_physics.value.x = 1e30;
  send_cmd(c, "set_target_angular_velocity 1e30 rad/s");
  {
    static lockstep_msg_CurvePoint curve[32];
    static lockstep_msg_GearPhysicsControl gears[16];
    for (int i = 0; i < 32; ++i) {
      curve[i].x = i * 100.0;
      curve[i].y = 300;
    }
    for (int i = 0; i < 16; ++i) {
      gears[i].ratio = 1;
      gears[i].down_ratio = 0.5;
      gears[i].up_ratio = 0.6;
    }
    curve[7].y = nan;
    c = fresh(lockstep_msg_CMD_VEHICLE_PHYSICS);
    lockstep_msg_VehiclePhysicsControl *p = &c->body._u.vehicle_physics.physics;
    c->body._u.vehicle_physics.actor = t->vehicle;
    p->torque_curve._length = p->torque_curve._maximum = 32;
    p->torque_curve._buffer = curve;
    p->forward_gears._length = p->forward_gears._maximum = 16;
    p->forward_gears._buffer = gears;
    p->max_rpm = 6000;
    p->moi = 1;
    p->final_ratio = 4;
    p->mass = 1500;
    p->tire_friction = 3;
    p->wheel_radius = 0.35;
    p->max_steer_angle = 1.2;
    p->max_brake_torque = 1500;
    p->max_handbrake_torque = 3000;
    p->suspension_stiffness = 30000;
    p->suspension_damping = 3000;
    p->wheelbase = 2.8;
    p->track = 1.6;
    p->clutch_strength = 10;
    send_cmd(c, "vehicle physics with a NaN in its torque curve");
    curve[7].y = 300;
    p->wheel_radius = -inf;
    send_cmd(c, "vehicle physics with a wheel radius of -infinity");
    p->wheel_radius = 0.35;
    p->center_of_mass.z = nan;
    send_cmd(c, "vehicle physics with a NaN centre of mass");
    p->center_of_mass.z = 0;
    p->suspension_stiffness = -5;
    p->max_steer_angle = 1e9;
    send_cmd(c, "[service] vehicle physics with a negative stiffness and a steer angle of 1e9 rad");
  }
  c = fresh(lockstep_msg_CMD_WALKER_AI);
  c->body._u.walker_ai.actor = t->vehicle;
  c->body._u.walker_ai.kind = lockstep_msg_WALKER_AI_GO_TO_LOCATION;
  c->body._u.walker_ai.location.x = nan;
  send_cmd(c, "walker AI go_to_location NaN");
  c = fresh(lockstep_msg_CMD_PEDESTRIANS);
  c->body._u.pedestrians.cross_factor = inf;
  send_cmd(c, "pedestrians cross factor infinite");

  /* debug, recorder, V2X */
  c = fresh(lockstep_msg_CMD_DEBUG_DRAW);
  for (int i = 0; i < 4096; ++i) {
    memset(&shapes[i], 0, sizeof shapes[i]);
    shapes[i].kind = lockstep_msg_DEBUG_POINT;
    shapes[i].size = 0.1;
    shapes[i].rotation.w = 1;
  }
  shapes[4095].end.y = nan;
  c->body._u.debug_draw.shapes._length = c->body._u.debug_draw.shapes._maximum = 4096;
  c->body._u.debug_draw.shapes._buffer = shapes;
  send_cmd(c, "debug draw of 4096 shapes, the last NaN");
  c = fresh(lockstep_msg_CMD_DEBUG_DRAW);
  shapes[0].size = inf;
  c->body._u.debug_draw.shapes._length = c->body._u.debug_draw.shapes._maximum = 1;
  c->body._u.debug_draw.shapes._buffer = shapes;
  send_cmd(c, "debug draw of an infinite point");
  c = fresh(lockstep_msg_CMD_RECORDER);
  c->body._u.recorder.action = lockstep_msg_RECORDER_START;
  send_cmd(c, "start_recorder without a name");
  c = fresh(lockstep_msg_CMD_V2X_SEND);
  c->body._u.v2x_send.sensor = t->vehicle;
  memset(c->body._u.v2x_send.data, 'v', 1024);
  send_cmd(c, "V2X send from a vehicle (not a V2X sensor)");

  /* (Values outside an enum's range, a union discriminator of no branch: Cyclone's writer
   * refuses to serialize them, "Bad Parameter", so no conforming participant sends them.) */
}

/* ---- the other topics ---- */

static void published(const char *topic, const char *label, dds_return_t rc) {
  if (rc < 0) {
    printf("unpublished %s %s: %s\n", topic, label, dds_strretcode(rc));
  } else {
    printf("published %s %s\n", topic, label);
  }
  fflush(stdout);
}

static void publish_others(const target *t, dds_duration_t match_timeout) {
  char host[65] = {0};
  gethostname(host, sizeof host - 1);
  /* Acks: an unknown service, another run, a frame far in the future, a past frame with
   * another hash and a divergence, for a live service. */
  dds_entity_t ack_w = writer(&lockstep_msg_Ack_desc, "lockstep/ack", false, 1);
  wait_matched(ack_w, match_timeout);
  lockstep_msg_Ack a;
  memset(&a, 0, sizeof a);
  snprintf(a.service, sizeof a.service, "intruder");
  a.run = t->run;
  a.frame = t->frame + 1;
  a.state_hash = 0xdeadbeef;
  published("lockstep/ack", "an unknown service", dds_write(ack_w, &a));
  snprintf(a.service, sizeof a.service, "%s", t->service);
  a.run = t->run + 1000;
  a.frame = 3;
  published("lockstep/ack", "another run's id", dds_write(ack_w, &a));
  a.run = t->run;
  a.frame = t->frame + 1000000;
  a.replay_from = t->frame + 1000000;
  a.step_wall_us = NAN;
  published("lockstep/ack", "a frame from the future", dds_write(ack_w, &a));
  a.frame = t->frame > 3 ? t->frame - 3 : 1;
  a.replay_from = 0;
  a.state_hash = 0x0badc0de;
  snprintf(a.divergence, sizeof a.divergence, "hostile: a divergence that is not");
  published("lockstep/ack", "a frame from the past with another hash and a divergence", dds_write(ack_w, &a));

  /* Announcements: the live service's name from another process, ready and then stopping;
   * an unknown kind with NaN-free garbage. */
  dds_entity_t ann_w = writer(&lockstep_msg_ServiceAnnounce_desc, "lockstep/service", true, 1);
  wait_matched(ann_w, match_timeout);
  lockstep_msg_ServiceAnnounce s;
  memset(&s, 0, sizeof s);
  snprintf(s.service, sizeof s.service, "%s", t->service);
  snprintf(s.kind, sizeof s.kind, "hostile");
  s.state = lockstep_msg_SERVICE_READY;
  s.pid = (int32_t)getpid();
  memcpy(s.host, host, sizeof s.host);
  s.last_frame = t->frame + 1000000;
  published("lockstep/service", "a duplicate of a live service's name, ready", dds_write(ann_w, &s));
  s.state = lockstep_msg_SERVICE_STOPPING;
  snprintf(s.reason, sizeof s.reason, "hostile: a failure that is not");
  published("lockstep/service", "a duplicate of a live service's name, stopping", dds_write(ann_w, &s));

  /* Blueprints: 2000 declarations under an unknown name (20 times a town's), one of them a
   * live blueprint; then one under a live service's name. */
  dds_entity_t bp_w = writer(&lockstep_msg_BlueprintSet_desc, "lockstep/blueprints", true, 1);
  wait_matched(bp_w, match_timeout);
  {
    const uint32_t n = 2000;
    lockstep_msg_BlueprintDeclaration *bps = calloc(n, sizeof *bps);
    if (!bps) die("out of memory", DDS_RETCODE_OUT_OF_RESOURCES);
    for (uint32_t i = 0; i < n; ++i) {
      snprintf(bps[i].id, sizeof bps[i].id, "prop.hostile.%u", i);
      bps[i].kind = lockstep_msg_ACTOR_PROP;
      bps[i].half_extents.x = NAN;
    }
    snprintf(bps[0].id, sizeof bps[0].id, "drone.generic_quad");
    lockstep_msg_BlueprintSet set;
    memset(&set, 0, sizeof set);
    snprintf(set.service, sizeof set.service, "intruder");
    set.blueprints._length = set.blueprints._maximum = n;
    set.blueprints._buffer = bps;
    published("lockstep/blueprints", "2000 declarations by an unknown service", dds_write(bp_w, &set));
    snprintf(set.service, sizeof set.service, "%s", t->service);
    set.blueprints._length = 1;
    published("lockstep/blueprints", "a live service's name declaring another's blueprint", dds_write(bp_w, &set));
    free(bps);
  }

  /* A snapshot of 2 MiB of garbage for a live service, of another run and of this one. */
  dds_entity_t snap_w = writer(&lockstep_msg_ServiceSnapshot_desc, "lockstep/snapshot", true, 1);
  wait_matched(snap_w, match_timeout);
  {
    const uint32_t n = 2u << 20;
    uint8_t *bytes = malloc(n);
    if (!bytes) die("out of memory", DDS_RETCODE_OUT_OF_RESOURCES);
    for (uint32_t i = 0; i < n; ++i) bytes[i] = (uint8_t)(i * 2654435761u >> 13);
    lockstep_msg_ServiceSnapshot snap;
    memset(&snap, 0, sizeof snap);
    snprintf(snap.service, sizeof snap.service, "%s", t->service);
    snap.run = t->run + 7;
    snap.frame = 1;
    snap.state._length = snap.state._maximum = n;
    snap.state._buffer = bytes;
    published("lockstep/snapshot", "2 MiB of garbage, another run", dds_write(snap_w, &snap));
    snap.run = t->run;
    snap.frame = t->frame + 500000;
    published("lockstep/snapshot", "2 MiB of garbage, a future frame", dds_write(snap_w, &snap));
    free(bytes);
  }

  /* World state: another run, the future, the past, 100k NaN vehicles and drones. */
  dds_entity_t ground_w = writer(&lockstep_msg_GroundState_desc, "lockstep/ground_state", true, 256);
  dds_entity_t air_w = writer(&lockstep_msg_AirState_desc, "lockstep/air_state", true, 256);
  wait_matched(ground_w, match_timeout);
  wait_matched(air_w, match_timeout);
  {
    const uint32_t n = 2000;
    lockstep_msg_VehicleState *vs = calloc(n, sizeof *vs);
    lockstep_msg_DroneState *ds = calloc(n, sizeof *ds);
    if (!vs || !ds) die("out of memory", DDS_RETCODE_OUT_OF_RESOURCES);
    for (uint32_t i = 0; i < n; ++i) {
      vs[i].actor = t->vehicle;
      vs[i].transform.position.x = NAN;
      vs[i].transform.orientation.w = INFINITY;
      ds[i].actor = t->drone;
      ds[i].transform.position.z = -INFINITY;
      ds[i].transform.orientation.w = NAN;
    }
    lockstep_msg_GroundState g;
    memset(&g, 0, sizeof g);
    g.vehicles._length = g.vehicles._maximum = n;
    g.vehicles._buffer = vs;
    lockstep_msg_AirState air;
    memset(&air, 0, sizeof air);
    air.drones._length = air.drones._maximum = n;
    air.drones._buffer = ds;
    const struct {
      uint32_t run;
      uint64_t frame;
      const char *label;
    } stamps[] = {{t->run + 1000, t->frame + 2, "another run's id"},
                  {t->run, t->frame + 100000, "a frame from the future"},
                  {t->run, 1, "frame 1 (the past)"},
                  {t->run, t->frame > 2 ? t->frame - 2 : 1, "a recent past frame"}};
    for (size_t i = 0; i < sizeof stamps / sizeof stamps[0]; ++i) {
      char label[160];
      snprintf(label, sizeof label, "%s, 2000 NaN vehicles", stamps[i].label);
      g.stamp.run = air.stamp.run = stamps[i].run;
      g.stamp.frame = air.stamp.frame = stamps[i].frame;
      g.stamp.sim_time = air.stamp.sim_time = NAN;
      g.state_hash = air.state_hash = 0xbad;
      published("lockstep/ground_state", label, dds_write(ground_w, &g));
      snprintf(label, sizeof label, "%s, 2000 NaN drones", stamps[i].label);
      published("lockstep/air_state", label, dds_write(air_w, &air));
    }
    free(vs);
    free(ds);
  }
  /* Give the reliable writers time to deliver before the participant goes (samples of a
   * deleted writer may be dropped): wait until the readers acknowledged everything. */
  dds_wait_for_acks(ground_w, DDS_SECS(10));
  dds_wait_for_acks(air_w, DDS_SECS(10));
  dds_wait_for_acks(snap_w, DDS_SECS(10));
  dds_wait_for_acks(bp_w, DDS_SECS(10));
  dds_wait_for_acks(ann_w, DDS_SECS(5));
  dds_wait_for_acks(ack_w, DDS_SECS(5));
}

static void take_replies(dds_entity_t reply_reader, int *replies) {
  void *samples[16] = {NULL};
  dds_sample_info_t infos[16];
  int32_t n;
  while ((n = dds_take(reply_reader, samples, infos, 16, 16)) > 0) {
    for (int32_t i = 0; i < n; ++i) {
      const lockstep_msg_CommandReply *r = samples[i];
      if (!infos[i].valid_data || strcmp(r->client, CLIENT) != 0) continue;
      for (int k = 0; k < g_n_sent; ++k) {
        if (g_sent[k].seq == r->sequence_number && !g_sent[k].replied) {
          g_sent[k].replied = true;
          ++*replies;
          printf("reply %" PRIu64 " accepted=%d reason=%s\n", r->sequence_number, (int)r->accepted, r->reason);
          fflush(stdout);
        }
      }
    }
    dds_return_loan(reply_reader, samples, n);
    memset(samples, 0, sizeof samples);
  }
}

int main(int argc, char **argv) {
  int domain = 0;
  uint64_t after = 10;
  double timeout_s = 30;
  for (int i = 1; i < argc; ++i) {
    if (strcmp(argv[i], "--domain") == 0 && i + 1 < argc) {
      domain = atoi(argv[++i]);
    } else if (strcmp(argv[i], "--after") == 0 && i + 1 < argc) {
      after = strtoull(argv[++i], NULL, 10);
    } else if (strcmp(argv[i], "--timeout") == 0 && i + 1 < argc) {
      timeout_s = atof(argv[++i]);
    } else {
      fprintf(stderr, "usage: lockstep_hostile_participant [--domain N] [--after FRAME] [--timeout S]\n");
      return 2;
    }
  }
  const dds_duration_t timeout = (dds_duration_t)(timeout_s * 1e9);
  g_dp = check(dds_create_participant((dds_domainid_t)domain, NULL, NULL), "participant");
  dds_entity_t status_r = reader(&lockstep_msg_RunStatus_desc, "lockstep/run_status", true, 1);
  dds_entity_t actors_r = reader(&lockstep_msg_ActorList_desc, "lockstep/actors", true, 1);
  dds_entity_t reply_r = reader(&lockstep_msg_CommandReply_desc, "lockstep/command_reply", false, 256);
  g_command_writer = writer(&lockstep_msg_Command_desc, "lockstep/command", false, 256);

  target t;
  memset(&t, 0, sizeof t);
  const dds_time_t end = dds_time() + timeout;
  bool ready = false;
  while (dds_time() < end && !ready) {
    const bool running = read_status(status_r, &t, after);
    read_actors(actors_r, &t);
    ready = running && t.vehicle != 0 && t.drone != 0;
    if (!ready) dds_sleepfor(DDS_MSECS(20));
  }
  if (!ready || !wait_matched(g_command_writer, timeout)) {
    fprintf(stderr, "lockstep_hostile_participant: no running simulation with a vehicle and a drone on domain %d\n", domain);
    return 2;
  }
  /* The reply reader must have matched the coordinator's writer too (VOLATILE). */
  const dds_time_t match_end = dds_time() + timeout;
  for (;;) {
    dds_subscription_matched_status_t st;
    if (dds_get_subscription_matched_status(reply_r, &st) == 0 && st.current_count > 0) break;
    if (dds_time() > match_end) {
      fprintf(stderr, "lockstep_hostile_participant: the reply reader matched no writer\n");
      return 2;
    }
    dds_sleepfor(DDS_MSECS(20));
  }
  printf("target run=%" PRIu32 " frame=%" PRIu64 " vehicle=%" PRIu32 " drone=%" PRIu32 " service=%s\n", t.run, t.frame,
         t.vehicle, t.drone, t.service);
  fflush(stdout);
  send_commands(&t);
  publish_others(&t, timeout);

  int replies = 0;
  int expected = 0;
  for (int k = 0; k < g_n_sent; ++k) expected += g_sent[k].replied ? 0 : 1;
  const dds_time_t reply_end = dds_time() + timeout;
  while (replies < expected && dds_time() < reply_end) {
    take_replies(reply_r, &replies);
    if (replies < expected) dds_sleepfor(DDS_MSECS(20));
  }
  for (int k = 0; k < g_n_sent; ++k) {
    if (!g_sent[k].replied) printf("missing %" PRIu64 " %s\n", g_sent[k].seq, g_sent[k].label);
  }
  printf("finished sent=%d replies=%d\n", g_n_sent, replies);
  fflush(stdout);
  dds_delete(g_dp);
  return 0;
}
