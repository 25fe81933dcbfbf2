/* cyclone_image_reader: a Cyclone DDS reader of one camera's Image topic, for the test
 * that a client on another DDS vendor receives the frames the render service publishes
 * with Fast DDS (data-sharing between Fast DDS processes, UDP to everything else).
 *
 *   cyclone_image_reader --domain N --topic NAME [--count K] [--timeout-s S]
 *
 * Prints "ready" once its reader exists, then one line per sample received:
 *   image <sensor> <frame> <width> <height> <encoding> <bytes> <fnv1a32 of the bytes>
 * and exits 0 after K samples (default 1), 1 on timeout (default 30 s).
 * QoS as deploy/qos/fastdds.xml's image reader: RELIABLE, TRANSIENT_LOCAL, KEEP_LAST 2.
 * Network settings come from CYCLONEDDS_URI (client/cyclone_c/cyclone_loopback.xml). */
#define _POSIX_C_SOURCE 200809L

#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dds/dds.h"
#include "lockstep/sensor.h"

static uint32_t fnv1a32(const uint8_t *p, uint32_t n) {
  uint32_t h = 2166136261u;
  for (uint32_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 16777619u;
  }
  return h;
}

int main(int argc, char **argv) {
  int domain = 0, count = 1, timeout_s = 30;
  const char *topic = NULL;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (strcmp(argv[i], "--domain") == 0) domain = atoi(argv[i + 1]);
    else if (strcmp(argv[i], "--topic") == 0) topic = argv[i + 1];
    else if (strcmp(argv[i], "--count") == 0) count = atoi(argv[i + 1]);
    else if (strcmp(argv[i], "--timeout-s") == 0) timeout_s = atoi(argv[i + 1]);
    else {
      fprintf(stderr, "cyclone_image_reader: unknown argument '%s'\n", argv[i]);
      return 2;
    }
  }
  if (!topic || count < 1 || timeout_s < 1) {
    fprintf(stderr, "usage: cyclone_image_reader --domain N --topic NAME [--count K] [--timeout-s S]\n");
    return 2;
  }
  const dds_entity_t dp = dds_create_participant((dds_domainid_t)domain, NULL, NULL);
  if (dp < 0) {
    fprintf(stderr, "cyclone_image_reader: participant: %s\n", dds_strretcode(dp));
    return 1;
  }
  const dds_entity_t tp = dds_create_topic(dp, &lockstep_msg_Image_desc, topic, NULL, NULL);
  dds_qos_t *q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 2);
  const dds_entity_t rd = tp < 0 ? tp : dds_create_reader(dp, tp, q, NULL);
  dds_delete_qos(q);
  if (rd < 0) {
    fprintf(stderr, "cyclone_image_reader: topic or reader '%s': %s\n", topic, dds_strretcode(rd));
    dds_delete(dp);
    return 1;
  }
  const dds_entity_t ws = dds_create_waitset(dp);
  const dds_entity_t cond = dds_create_readcondition(rd, DDS_ANY_STATE);
  dds_waitset_attach(ws, cond, rd);
  printf("ready\n");
  fflush(stdout);
  int got = 0;
  const dds_time_t deadline = dds_time() + DDS_SECS(timeout_s);
  while (got < count && dds_time() < deadline) {
    dds_waitset_wait_until(ws, NULL, 0, deadline);
    void *samples[4] = {NULL};
    dds_sample_info_t infos[4];
    const int32_t n = dds_take(rd, samples, infos, 4, 4);
    for (int32_t i = 0; i < n && got < count; ++i) {
      if (!infos[i].valid_data) continue;
      const lockstep_msg_Image *im = samples[i];
      printf("image %" PRIu32 " %" PRIu64 " %" PRIu32 " %" PRIu32 " %" PRIu32 " %" PRIu32 " %" PRIu32 "\n", im->sensor,
             im->stamp.frame, im->width, im->height, im->encoding, im->data._length, fnv1a32(im->data._buffer, im->data._length));
      ++got;
    }
    if (n > 0) dds_return_loan(rd, samples, n);
    fflush(stdout);
  }
  dds_delete(dp);
  return got >= count ? 0 : 1;
}
