/* A ROS 2 node's view of a Lockstep run, without ROS 2: a Cyclone DDS (C) participant
 * that uses the ROS 2 type names of idl/ros2/ (sensor_msgs::msg::dds_::Image_, ...) on
 * the topics of CARLA's native ROS 2 interface, as `ros2 topic echo` would. It checks:
 *   - rt/carla/<role>/<camera>/image: encoding bgra8, width/height as spawned, step = 4 w,
 *     data = step h bytes, frame_id = the camera's ROS name, stamp = a frame's simulation
 *     time (k dt, converted as CARLA does) that rt/clock also published;
 *   - .../camera_info: the pinhole of the camera's fov;
 *   - rt/carla/<role>/<lidar>: PointCloud2 x, y, z, intensity float32 at 0, 4, 8, 12,
 *     point_step 16, row_step = 16 width, height 1, frame_id, stamp as above;
 *   - an image and a point cloud of the same frame (equal stamps);
 *   - rt/carla/map: the OpenDRIVE text;
 * then sends carla_msgs/CarlaEgoVehicleControl (throttle) on
 * rt/carla/<role>/vehicle_control_cmd and waits until the vehicle's GNSS
 * (rt/carla/<role>/<gnss>, NavSatFix) has moved by --move-m metres.
 * Prints "ROS2 READER PASS" and exits 0, or "FAIL: ..." and exits 1. */
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "dds/dds.h"
#include "ros2/carla_msgs.h"
#include "ros2/rosgraph_msgs.h"
#include "ros2/sensor_msgs.h"
#include "ros2/std_msgs.h"

#define MAX_STAMPS 4096

static struct {
  int domain;
  const char *role, *camera, *lidar, *gnss;
  unsigned width, height;
  double dt, fov_deg, timeout_s, move_m;
  int images_before_control;
} opt = {0, "hero", "front", "lidar", "gnss", 64, 48, 0.05, 90.0, 120.0, 2.0, 3};

typedef struct {
  int32_t sec;
  uint32_t nanosec;
} stamp_t;

static stamp_t clocks[MAX_STAMPS], images[MAX_STAMPS], clouds[MAX_STAMPS];
static int n_clocks, n_images, n_clouds, n_infos;

static double now_s(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + (double)ts.tv_nsec * 1e-9;
}

static void fail(const char *what, const char *detail) {
  printf("FAIL: %s%s%s\n", what, detail ? ": " : "", detail ? detail : "");
  fflush(stdout);
  exit(1);
}

/* CARLA's ROS2::SetTimestamp of a simulation time. */
static stamp_t carla_stamp(double t) {
  double integral;
  const double fractional = modf(t, &integral);
  stamp_t s = {(int32_t)integral, (uint32_t)(fractional * 1000000000.0)};
  return s;
}

/* The stamp must be the simulation time of a frame k >= 1: k dt up to the rounding of
 * the coordinator's running sum (sim_time of k = sim_time of k-1 + dt), converted as CARLA
 * converts it. That it is exactly the time the bridge published on rt/clock for that
 * frame is checked once the run has been seen (clock and data arrive on different topics). */
static void check_stamp(const char *what, const struct builtin_interfaces_msg_dds__Time_ *t) {
  const double seconds = (double)t->sec + (double)t->nanosec * 1e-9;
  const double k = round(seconds / opt.dt);
  const stamp_t want = carla_stamp(k * opt.dt);
  if (k < 1 || fabs(seconds - k * opt.dt) > 1e-6 || t->nanosec >= 1000000000u) {
    char d[160];
    snprintf(d, sizeof d, "stamp %d.%09u is not a frame's simulation time (k dt = %d.%09u, dt %g)", t->sec, t->nanosec, want.sec,
             want.nanosec, opt.dt);
    fail(what, d);
  }
}

static void check_frame_id(const char *what, const char *got, const char *want) {
  if (got == NULL || strcmp(got, want) != 0) {
    char d[160];
    snprintf(d, sizeof d, "frame_id '%s', expected '%s'", got ? got : "(null)", want);
    fail(what, d);
  }
}

static bool before(stamp_t a, stamp_t b) { return a.sec < b.sec || (a.sec == b.sec && a.nanosec < b.nanosec); }

static bool contains(const stamp_t *set, int n, stamp_t s) {
  for (int i = 0; i < n; ++i)
    if (set[i].sec == s.sec && set[i].nanosec == s.nanosec) return true;
  return false;
}

static dds_entity_t reader(dds_entity_t pp, const dds_topic_descriptor_t *desc, const char *name, bool transient_local) {
  dds_entity_t topic = dds_create_topic(pp, desc, name, NULL, NULL);
  if (topic < 0) fail("dds_create_topic", name);
  dds_qos_t *q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 16);
  dds_entity_t r = dds_create_reader(pp, topic, q, NULL);
  dds_delete_qos(q);
  if (r < 0) fail("dds_create_reader", name);
  return r;
}

/* Takes what is there; calls `on` for each valid sample. */
#define TAKE(r, T, on)                                                    \
  do {                                                                    \
    void *samples_[16] = {0};                                             \
    dds_sample_info_t infos_[16];                                         \
    const int n_ = dds_take((r), samples_, infos_, 16, 16);               \
    for (int i_ = 0; i_ < n_; ++i_) {                                     \
      if (infos_[i_].valid_data) on((const T *)samples_[i_]);             \
    }                                                                     \
    if (n_ > 0) dds_return_loan((r), samples_, n_);                       \
  } while (0)

static void on_clock(const rosgraph_msgs_msg_dds__Clock_ *c) {
  if (n_clocks < MAX_STAMPS) clocks[n_clocks++] = (stamp_t){c->clock.sec, c->clock.nanosec};
}

static void on_image(const sensor_msgs_msg_dds__Image_ *m) {
  char d[200];
  if (strcmp(m->encoding, "bgra8") != 0) {
    snprintf(d, sizeof d, "encoding '%s', expected 'bgra8'", m->encoding);
    fail("image", d);
  }
  if (m->width != opt.width || m->height != opt.height || m->step != 4 * opt.width || m->is_bigendian != 0 ||
      m->data._length != (uint32_t)m->step * m->height) {
    snprintf(d, sizeof d, "%ux%u step %u bigendian %u, %u bytes; expected %ux%u step %u, %u bytes", m->width, m->height, m->step,
             m->is_bigendian, m->data._length, opt.width, opt.height, 4 * opt.width, 4 * opt.width * opt.height);
    fail("image", d);
  }
  check_frame_id("image", m->header.frame_id, opt.camera);
  check_stamp("image", &m->header.stamp);
  if (n_images < MAX_STAMPS) images[n_images++] = (stamp_t){m->header.stamp.sec, m->header.stamp.nanosec};
}

static void on_info(const sensor_msgs_msg_dds__CameraInfo_ *m) {
  const double fx = opt.width / (2.0 * tan(opt.fov_deg * M_PI / 360.0));
  if (m->width != opt.width || m->height != opt.height || strcmp(m->distortion_model, "plumb_bob") != 0 ||
      fabs(m->k[0] - fx) > 1e-9 || fabs(m->k[4] - fx) > 1e-9 || m->k[2] != opt.width / 2.0 || m->k[5] != opt.height / 2.0 ||
      m->k[8] != 1.0) {
    char d[200];
    snprintf(d, sizeof d, "%ux%u '%s' fx %g cx %g cy %g; expected fx %g", m->width, m->height, m->distortion_model, m->k[0], m->k[2],
             m->k[5], fx);
    fail("camera_info", d);
  }
  check_frame_id("camera_info", m->header.frame_id, opt.camera);
  check_stamp("camera_info", &m->header.stamp);
  ++n_infos;
}

static void on_cloud(const sensor_msgs_msg_dds__PointCloud2_ *m) {
  static const char *names[4] = {"x", "y", "z", "intensity"};
  char d[200];
  if (m->fields._length != 4) {
    snprintf(d, sizeof d, "%u fields, expected 4 (x, y, z, intensity)", m->fields._length);
    fail("point cloud", d);
  }
  for (uint32_t i = 0; i < 4; ++i) {
    const struct sensor_msgs_msg_dds__PointField_ *f = &m->fields._buffer[i];
    if (strcmp(f->name, names[i]) != 0 || f->offset != 4 * i || f->datatype != 7 /* FLOAT32 */ || f->count != 1) {
      snprintf(d, sizeof d, "field %u is '%s' at %u type %u count %u, expected '%s' at %u FLOAT32 (7) count 1", i, f->name, f->offset,
               f->datatype, f->count, names[i], 4 * i);
      fail("point cloud", d);
    }
  }
  if (m->height != 1 || m->point_step != 16 || m->row_step != 16 * m->width || m->is_bigendian ||
      m->data._length != m->row_step * m->height) {
    snprintf(d, sizeof d, "height %u width %u point_step %u row_step %u, %u bytes", m->height, m->width, m->point_step, m->row_step,
             m->data._length);
    fail("point cloud", d);
  }
  check_frame_id("point cloud", m->header.frame_id, opt.lidar);
  check_stamp("point cloud", &m->header.stamp);
  if (m->width > 0 && n_clouds < MAX_STAMPS) clouds[n_clouds++] = (stamp_t){m->header.stamp.sec, m->header.stamp.nanosec};
}

static bool have_fix, have_map;
static double lat, lon, lat0, lon0;
static void on_gnss(const sensor_msgs_msg_dds__NavSatFix_ *m) {
  check_frame_id("gnss", m->header.frame_id, opt.gnss);
  check_stamp("gnss", &m->header.stamp);
  lat = m->latitude;
  lon = m->longitude;
  have_fix = true;
}

static void on_map(const std_msgs_msg_dds__String_ *m) {
  if (m->data == NULL || strstr(m->data, "<OpenDRIVE") == NULL) fail("map", "rt/carla/map holds no OpenDRIVE text");
  have_map = true;
}

static double metres(double la0, double lo0, double la1, double lo1) {
  const double dn = (la1 - la0) * 111320.0, de = (lo1 - lo0) * 111320.0 * cos(la0 * M_PI / 180.0);
  return sqrt(dn * dn + de * de);
}

int main(int argc, char **argv) {
  for (int i = 1; i + 1 < argc; i += 2) {
    const char *k = argv[i], *v = argv[i + 1];
    if (!strcmp(k, "--domain")) opt.domain = atoi(v);
    else if (!strcmp(k, "--role")) opt.role = v;
    else if (!strcmp(k, "--camera")) opt.camera = v;
    else if (!strcmp(k, "--lidar")) opt.lidar = v;
    else if (!strcmp(k, "--gnss")) opt.gnss = v;
    else if (!strcmp(k, "--width")) opt.width = (unsigned)atoi(v);
    else if (!strcmp(k, "--height")) opt.height = (unsigned)atoi(v);
    else if (!strcmp(k, "--dt")) opt.dt = atof(v);
    else if (!strcmp(k, "--fov")) opt.fov_deg = atof(v);
    else if (!strcmp(k, "--timeout")) opt.timeout_s = atof(v);
    else if (!strcmp(k, "--move-m")) opt.move_m = atof(v);
    else {
      fprintf(stderr, "ros2_reader: unknown option %s\n", k);
      return 2;
    }
  }
  char base[256], name[320];
  snprintf(base, sizeof base, "rt/carla/%s", opt.role);
  dds_entity_t pp = dds_create_participant((dds_domainid_t)opt.domain, NULL, NULL);
  if (pp < 0) fail("dds_create_participant", NULL);
  const dds_entity_t r_clock = reader(pp, &rosgraph_msgs_msg_dds__Clock__desc, "rt/clock", false);
  const dds_entity_t r_map = reader(pp, &std_msgs_msg_dds__String__desc, "rt/carla/map", true);
  snprintf(name, sizeof name, "%s/%s/image", base, opt.camera);
  const dds_entity_t r_image = reader(pp, &sensor_msgs_msg_dds__Image__desc, name, false);
  snprintf(name, sizeof name, "%s/%s/camera_info", base, opt.camera);
  const dds_entity_t r_info = reader(pp, &sensor_msgs_msg_dds__CameraInfo__desc, name, false);
  snprintf(name, sizeof name, "%s/%s", base, opt.lidar);
  const dds_entity_t r_cloud = reader(pp, &sensor_msgs_msg_dds__PointCloud2__desc, name, false);
  snprintf(name, sizeof name, "%s/%s", base, opt.gnss);
  const dds_entity_t r_gnss = reader(pp, &sensor_msgs_msg_dds__NavSatFix__desc, name, false);
  snprintf(name, sizeof name, "%s/vehicle_control_cmd", base);
  const dds_entity_t t_control = dds_create_topic(pp, &carla_msgs_msg_dds__CarlaEgoVehicleControl__desc, name, NULL, NULL);
  dds_qos_t *wq = dds_create_qos();
  dds_qset_reliability(wq, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(wq, DDS_DURABILITY_VOLATILE);
  dds_qset_history(wq, DDS_HISTORY_KEEP_LAST, 8);
  const dds_entity_t w_control = dds_create_writer(pp, t_control, wq, NULL);
  dds_delete_qos(wq);
  if (t_control < 0 || w_control < 0) fail("dds_create_writer", name);

  const dds_entity_t waitset = dds_create_waitset(pp);
  const dds_entity_t all[] = {r_clock, r_map, r_image, r_info, r_cloud, r_gnss};
  for (size_t i = 0; i < sizeof all / sizeof all[0]; ++i) {
    dds_set_status_mask(all[i], DDS_DATA_AVAILABLE_STATUS);
    dds_waitset_attach(waitset, all[i], all[i]);
  }
  const double start = now_s();
  bool controlled = false, paired = false;
  double last_send = 0;
  while (now_s() - start < opt.timeout_s) {
    TAKE(r_clock, rosgraph_msgs_msg_dds__Clock_, on_clock);
    TAKE(r_map, std_msgs_msg_dds__String_, on_map);
    TAKE(r_image, sensor_msgs_msg_dds__Image_, on_image);
    TAKE(r_info, sensor_msgs_msg_dds__CameraInfo_, on_info);
    TAKE(r_cloud, sensor_msgs_msg_dds__PointCloud2_, on_cloud);
    TAKE(r_gnss, sensor_msgs_msg_dds__NavSatFix_, on_gnss);
    for (int i = 0; i < n_images && !paired; ++i) paired = contains(clouds, n_clouds, images[i]);
    const bool seen = n_images >= opt.images_before_control && n_clouds >= opt.images_before_control && n_infos > 0 && paired &&
                      have_fix && have_map;
    if (seen && !controlled) {
      dds_publication_matched_status_t st;
      if (dds_get_publication_matched_status(w_control, &st) == 0 && st.current_count > 0) {
        lat0 = lat;
        lon0 = lon;
        controlled = true;
        printf("SEEN images %d (camera_info %d), point clouds %d, clock %d; sending vehicle_control_cmd\n", n_images, n_infos, n_clouds,
               n_clocks);
        fflush(stdout);
      }
    }
    if (controlled && now_s() - last_send > 0.2) {  /* throttle as a ROS 2 controller sends it, a few times a second */
      carla_msgs_msg_dds__CarlaEgoVehicleControl_ c;
      memset(&c, 0, sizeof c);
      c.header.frame_id = (char *)"";
      c.throttle = 1.0f;
      if (dds_write(w_control, &c) < 0) fail("dds_write", "vehicle_control_cmd");
      last_send = now_s();
    }
    if (controlled && metres(lat0, lon0, lat, lon) >= opt.move_m) {
      /* Every stamp checked (from the first clock this reader heard on) must also be a time
       * the bridge published on rt/clock. */
      for (int i = 0; i < n_images; ++i)
        if (n_clocks > 0 && !before(images[i], clocks[0]) && !contains(clocks, n_clocks, images[i])) fail("image", "stamp never published on rt/clock");
      for (int i = 0; i < n_clouds; ++i)
        if (n_clocks > 0 && !before(clouds[i], clocks[0]) && !contains(clocks, n_clocks, clouds[i]))
          fail("point cloud", "stamp never published on rt/clock");
      if (n_clocks == 0) fail("clock", "nothing on rt/clock");
      printf("MOVED %.2f m after vehicle_control_cmd\n", metres(lat0, lon0, lat, lon));
      printf("ROS2 READER PASS: %d images, %d point clouds, %d clock samples\n", n_images, n_clouds, n_clocks);
      fflush(stdout);
      dds_delete(pp);
      return 0;
    }
    dds_waitset_wait(waitset, NULL, 0, DDS_MSECS(100));  /* until a sample arrives (or the next control is due) */
  }
  printf("FAIL: timeout after %.0f s: images %d, camera_info %d, point clouds %d (paired %d), clock %d, gnss %d, map %d, controlled %d, moved %.2f m\n",
         opt.timeout_s, n_images, n_infos, n_clouds, paired, n_clocks, have_fix, have_map, controlled,
         controlled ? metres(lat0, lon0, lat, lon) : 0.0);
  dds_delete(pp);
  return 1;
}
