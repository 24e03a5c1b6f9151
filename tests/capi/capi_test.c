/* Uses the whole C API from a C99 program (compiled with -std=c99 -pedantic-errors). Exits non-zero
 * with a message on the first failed check. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scenelod/scenelod.h"

static int failures = 0;
#define CHECK(cond)                                                         \
  do {                                                                      \
    if (!(cond)) {                                                          \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                           \
    }                                                                       \
  } while (0)

static int callback_calls = 0;
static void onError(void* user, slod_status status, const char* message) {
  (void)user;
  (void)status;
  CHECK(message != NULL && message[0] != '\0');
  ++callback_calls;
}

/* a UV sphere of radius 1 with rings x segments quads */
static void makeSphere(int rings, int segments, float** positions, size_t* vertex_count, uint32_t** indices,
                       size_t* index_count) {
  int r, s;
  size_t v = 0, i = 0;
  *vertex_count = (size_t)(rings + 1) * (size_t)(segments + 1);
  *index_count = (size_t)rings * (size_t)segments * 6;
  *positions = (float*)malloc(*vertex_count * 3 * sizeof(float));
  *indices = (uint32_t*)malloc(*index_count * sizeof(uint32_t));
  for (r = 0; r <= rings; ++r) {
    const double theta = 3.14159265358979 * r / rings;
    for (s = 0; s <= segments; ++s) {
      const double phi = 2.0 * 3.14159265358979 * s / segments;
      (*positions)[v++] = (float)(sin(theta) * cos(phi));
      (*positions)[v++] = (float)cos(theta);
      (*positions)[v++] = (float)(sin(theta) * sin(phi));
    }
  }
  for (r = 0; r < rings; ++r)
    for (s = 0; s < segments; ++s) {
      const uint32_t a = (uint32_t)(r * (segments + 1) + s), b = a + (uint32_t)segments + 1;
      (*indices)[i++] = a; (*indices)[i++] = b; (*indices)[i++] = a + 1;
      (*indices)[i++] = a + 1; (*indices)[i++] = b; (*indices)[i++] = b + 1;
    }
}

int main(int argc, char** argv) {
  slod_context_desc cd;
  slod_context* ctx = NULL;
  slod_mesh_desc md;
  slod_chain_desc chd;
  slod_object_desc od;
  slod_object objects[64];
  slod_selection sel[64];
  slod_camera cam;
  slod_frame_params fp;
  slod_frame_result fr;
  slod_level_data ld;
  slod_pick_result pr;
  float* positions;
  uint32_t* indices;
  size_t vertex_count, index_count;
  uint32_t chain = 99, levels, l;
  int i, frame;
  const char* dir = argc > 1 ? argv[1] : ".";
  char replay_path[1024], pack_path[1024];

  CHECK(strcmp(slod_status_name(SLOD_OK), "ok") == 0);
  CHECK(slod_version_string()[0] != '\0');

  /* bad arguments never crash */
  CHECK(slod_context_create(NULL, &ctx) == SLOD_ERROR_INVALID_ARGUMENT);
  slod_context_desc_init(&cd);
  cd.max_objects = 0;
  CHECK(slod_context_create(&cd, &ctx) == SLOD_ERROR_INVALID_ARGUMENT);
  cd.max_objects = 64;
  cd.error_callback = onError;
  CHECK(slod_context_create(&cd, &ctx) == SLOD_OK && ctx != NULL);
  CHECK(slod_select(NULL, NULL, NULL, NULL, 0, NULL) == SLOD_ERROR_INVALID_ARGUMENT);

  /* a chain from caller memory */
  makeSphere(24, 48, &positions, &vertex_count, &indices, &index_count);
  slod_mesh_desc_init(&md);
  md.positions = positions;
  md.vertex_count = vertex_count;
  md.indices = indices;
  md.index_count = index_count;
  md.name = "sphere";
  slod_chain_desc_init(&chd);
  chd.level_count = 5;
  CHECK(slod_chain_build(ctx, &md, &chd, &chain) == SLOD_OK);
  CHECK(chain == 0);
  levels = slod_chain_level_count(ctx, chain);
  CHECK(levels == 6);
  for (l = 0; l < levels; ++l) {
    CHECK(slod_level_get(ctx, chain, l, &ld) == SLOD_OK);
    CHECK(ld.vertex_count > 0 && ld.positions != NULL);
    if (l == 0) CHECK(ld.triangle_count == index_count / 3 && ld.cell_width == 0.0f);
    if (l > 0) CHECK(ld.cell_width > 0.0f);
  }
  CHECK(slod_level_get(ctx, chain, levels, &ld) == SLOD_ERROR_NOT_FOUND);
  CHECK(strstr(slod_last_error_message(ctx), "levels") != NULL);

  /* bad meshes are refused with a message */
  indices[5] = 100000;
  CHECK(slod_chain_build(ctx, &md, &chd, &chain) == SLOD_ERROR_INVALID_MESH);
  CHECK(strstr(slod_last_error_message(ctx), "sphere") != NULL);
  indices[5] = 0;
  positions[4] = NAN;
  CHECK(slod_chain_build(ctx, &md, &chd, &chain) == SLOD_ERROR_INVALID_MESH);
  CHECK(slod_chain_load_file(ctx, "/nonexistent/model.glb", &chd, &chain) == SLOD_ERROR_IO);
  CHECK(slod_chain_count(ctx) == 1);
  CHECK(callback_calls >= 4);

  /* objects on a line along -z */
  for (i = 0; i < 40; ++i) {
    slod_object_desc_init(&od);
    od.chain = 0;
    od.translation[2] = -3.0f * (float)i;
    od.user_data = (uint64_t)(1000 + i);
    CHECK(slod_object_add(ctx, &od, &objects[i]) == SLOD_OK);
  }
  CHECK(slod_object_count(ctx) == 40);
  od.chain = 7;
  CHECK(slod_object_add(ctx, &od, &objects[40]) == SLOD_ERROR_NOT_FOUND);
  od.chain = 0;
  od.scale = -1.0f;
  CHECK(slod_object_add(ctx, &od, &objects[40]) == SLOD_ERROR_INVALID_ARGUMENT);

  slod_camera_init(&cam);
  cam.eye[2] = 4.0f;
  cam.target[2] = -10.0f;
  slod_frame_params_init(&fp);
  fp.budget_ms = 0.0f; /* distance mode */
  CHECK(slod_select(ctx, &cam, &fp, sel, 10, &fr) == SLOD_ERROR_CAPACITY);
  CHECK(slod_select(ctx, &cam, &fp, sel, 64, &fr) == SLOD_OK);
  for (i = 0; i < 40; ++i) {
    CHECK(sel[i].level >= -1 && sel[i].level < (int32_t)levels);
    CHECK(sel[i].user_data == (uint64_t)(1000 + i));
  }
  /* farther objects never get finer levels in distance mode */
  for (i = 1; i < 40; ++i)
    if (sel[i].level >= 0 && sel[i - 1].level >= 0) CHECK(sel[i].level >= sel[i - 1].level);
  CHECK(sel[0].level >= 0);

  /* picking hits the nearest object at its drawn level */
  CHECK(slod_pick(ctx, &cam, 640.0f, 360.0f, &pr) == SLOD_OK);
  CHECK(pr.object == objects[0]);
  CHECK(pr.level == sel[0].level);
  CHECK(fabsf(pr.distance - 3.0f) < 0.1f);

  /* budget mode with reported frame times, and recording */
  sprintf(replay_path, "%s/capi_replay.jsonl", dir);
  sprintf(pack_path, "%s/capi_scene.pack", dir);
  CHECK(slod_record_start(ctx, replay_path, pack_path) == SLOD_OK);
  CHECK(slod_object_remove(ctx, objects[3]) == SLOD_ERROR_UNSUPPORTED);
  fp.budget_ms = 2.0f;
  for (frame = 0; frame < 20; ++frame) {
    const float t[3] = {0.0f, 0.1f * (float)frame, 0.0f};
    const float q[4] = {0.0f, 0.0f, 0.0f, 1.0f};
    CHECK(slod_object_set_trs(ctx, objects[1], t, q, 1.0f) == SLOD_OK);
    CHECK(slod_select(ctx, &cam, &fp, sel, 64, &fr) == SLOD_OK);
    CHECK(fr.over_budget || fr.predicted_ms <= fp.budget_ms * 1.0001f);
    CHECK(slod_report_frame_time(ctx, fr.frame, 1.5f) == SLOD_OK);
  }
  CHECK(slod_record_stop(ctx) == SLOD_OK);
  CHECK(slod_record_stop(ctx) == SLOD_ERROR_UNSUPPORTED);

  /* removal makes the handle stale */
  CHECK(slod_object_remove(ctx, objects[3]) == SLOD_OK);
  CHECK(slod_object_remove(ctx, objects[3]) == SLOD_ERROR_NOT_FOUND);
  CHECK(slod_object_set_importance(ctx, objects[3], 2.0f) == SLOD_ERROR_NOT_FOUND);
  CHECK(slod_object_set_importance(ctx, objects[4], 2.0f) == SLOD_OK);
  CHECK(slod_object_count(ctx) == 39);
  CHECK(slod_select(ctx, &cam, &fp, sel, 64, &fr) == SLOD_OK);
  for (i = 0; i < 39; ++i) CHECK(sel[i].object != objects[3]);

  slod_context_destroy(ctx);
  free(positions);
  free(indices);
  if (failures) {
    fprintf(stderr, "%d checks failed\n", failures);
    return 1;
  }
  printf("capi_test: all checks passed\n");
  return 0;
}
