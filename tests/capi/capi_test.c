/* Uses the whole C API from a C99 program (compiled with -std=c99 -pedantic-errors), chains' whole
 * life included. Exits non-zero when a check failed, with a message per failed check. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scenelod/scenelod.h"
#include "test_support.h"

static int callback_calls = 0;
static void onError(void* user, slod_status status, const char* message) {
  (void)user;
  (void)status;
  CHECK(message != NULL && message[0] != '\0');
  ++callback_calls;
}

/* Chains are handles: destroying one that objects use is refused, destroying an unused one leaves the
 * others' objects selecting as before, and a destroyed chain's handle is stale even once its slot is
 * reused. `used` is a chain every object of ctx uses, `probe` one of them. */
static int checkChainLifecycle(slod_context* ctx, slod_chain used, const slod_mesh_desc* md, const slod_camera* cam,
                               const slod_frame_params* fp, slod_object probe) {
  const int before_failures = failures;
  slod_chain spare = SLOD_NULL_CHAIN, kept = SLOD_NULL_CHAIN, again = SLOD_NULL_CHAIN;
  slod_chain_desc chd;
  slod_object_desc od;
  slod_object kept_objects[4];
  slod_selection before[64], after[64];
  slod_level_data ld_before, ld_after;
  const uint32_t chains = slod_chain_count(ctx), n = slod_object_count(ctx) + 4;
  uint32_t i;

  slod_chain_desc_init(&chd);
  chd.level_count = 3;
  CHECK(slod_chain_build(ctx, md, &chd, &spare) == SLOD_OK);
  chd.method = SLOD_METHOD_UNIFORM;
  CHECK(slod_chain_build(ctx, md, &chd, &kept) == SLOD_OK);
  for (i = 0; i < 4; ++i) {
    slod_object_desc_init(&od);
    od.chain = kept;
    od.translation[0] = 2.0f;
    od.translation[2] = -4.0f * (float)i;
    CHECK(slod_object_add(ctx, &od, &kept_objects[i]) == SLOD_OK);
  }
  CHECK(slod_select(ctx, cam, fp, before, sizeof(slod_selection), 64, NULL) == SLOD_OK);
  slod_level_data_init(&ld_before);
  CHECK(slod_level_get(ctx, kept, 1, &ld_before) == SLOD_OK);

  CHECK(slod_chain_destroy(ctx, used) == SLOD_ERROR_IN_USE);
  CHECK(strstr(slod_last_error_message(ctx), "'sphere' is used by") != NULL);
  CHECK(slod_chain_level_count(ctx, used) > 0);
  CHECK(slod_chain_destroy(ctx, probe) == SLOD_ERROR_NOT_FOUND); /* an object handle is no chain handle */

  /* the spare chain sits before the kept one: destroying it moves the kept one's internal index */
  CHECK(slod_chain_destroy(ctx, spare) == SLOD_OK);
  CHECK(slod_chain_count(ctx) == chains + 1);
  CHECK(slod_chain_destroy(ctx, spare) == SLOD_ERROR_NOT_FOUND);
  CHECK(strstr(slod_last_error_message(ctx), "stale") != NULL);
  CHECK(slod_chain_level_count(ctx, spare) == 0);
  slod_level_data_init(&ld_after);
  CHECK(slod_level_get(ctx, spare, 0, &ld_after) == SLOD_ERROR_NOT_FOUND);
  od.chain = spare;
  CHECK(slod_object_add(ctx, &od, &kept_objects[0]) == SLOD_ERROR_NOT_FOUND);

  CHECK(slod_select(ctx, cam, fp, after, sizeof(slod_selection), 64, NULL) == SLOD_OK);
  for (i = 0; i < n; ++i) CHECK(after[i].object == before[i].object && after[i].level == before[i].level);
  CHECK(slod_level_get(ctx, kept, 1, &ld_after) == SLOD_OK);
  CHECK(ld_after.positions == ld_before.positions && ld_after.triangle_count == ld_before.triangle_count);

  /* the freed slot is reused with a new generation: the old handle stays stale */
  CHECK(slod_chain_build(ctx, md, &chd, &again) == SLOD_OK);
  CHECK(again != spare && (again & 0xffffffffu) == (spare & 0xffffffffu));
  CHECK(slod_chain_level_count(ctx, spare) == 0 && slod_chain_level_count(ctx, again) == 4);

  for (i = 0; i < 4; ++i) CHECK(slod_object_remove(ctx, kept_objects[i]) == SLOD_OK);
  CHECK(slod_chain_destroy(ctx, kept) == SLOD_OK);
  CHECK(slod_chain_destroy(ctx, again) == SLOD_OK);
  CHECK(slod_chain_count(ctx) == chains);
  return failures == before_failures;
}

/* A textured sphere with two materials (northern and southern half as two index ranges): level 0
 * gives back the input's UVs and ranges, every level streams of its vertex count and ranges that
 * cover its triangles, with their materials; the GENERIC kind is refused as not supported. */
static int checkAttributes(slod_context* ctx, const slod_mesh_desc* sphere) {
  const size_t vertex_count = sphere->vertex_count, index_count = sphere->index_count;
  float* uv = (float*)malloc(vertex_count * 2 * sizeof(float));
  slod_attribute_stream stream;
  slod_index_range ranges[2];
  slod_mesh_desc md;
  slod_chain_desc chd;
  slod_chain chain = SLOD_NULL_CHAIN;
  slod_level_data ld;
  slod_attribute_stream out;
  uint32_t l, r, covered;
  size_t v;
  for (v = 0; v < vertex_count; ++v) { /* the sphere's rings of 49 vertices: u along, v down */
    uv[2 * v] = (float)(v % 49) / 48.0f;
    uv[2 * v + 1] = (float)(v / 49) / 24.0f;
  }
  slod_attribute_stream_init(&stream);
  stream.kind = SLOD_ATTRIBUTE_UV;
  stream.set = 0;
  stream.component_count = 2;
  stream.data = uv;
  stream.count = vertex_count;
  ranges[0].first_index = 0;
  ranges[0].index_count = (uint32_t)(index_count / 2);
  ranges[0].material = 10;
  ranges[1].first_index = ranges[0].index_count;
  ranges[1].index_count = (uint32_t)(index_count - index_count / 2);
  ranges[1].material = 20;
  md = *sphere;
  md.name = "textured sphere";
  md.attributes = &stream;
  md.attribute_count = 1;
  md.ranges = ranges;
  md.range_count = 2;
  slod_chain_desc_init(&chd);
  chd.level_count = 3;
  CHECK(slod_chain_build(ctx, &md, &chd, &chain) == SLOD_OK);
  for (l = 0; l < slod_chain_level_count(ctx, chain); ++l) {
    slod_level_data_init(&ld);
    CHECK(slod_level_get(ctx, chain, l, &ld) == SLOD_OK);
    for (r = 0; r < ld.attribute_count; ++r) {
      slod_attribute_stream_init(&out);
      CHECK(slod_level_attribute_get(ctx, chain, l, r, &out) == SLOD_OK);
      CHECK(out.count == ld.vertex_count && out.data != NULL);
      if (l == 0) CHECK(out.kind == SLOD_ATTRIBUTE_UV && memcmp(out.data, uv, vertex_count * 2 * sizeof(float)) == 0);
    }
    for (r = 0, covered = 0; r < ld.range_count; ++r) {
      CHECK(ld.ranges[r].first_index == covered);
      CHECK(ld.ranges[r].material == (ld.ranges[r].source_range == 0 ? 10u : 20u));
      covered += ld.ranges[r].index_count;
    }
    CHECK(ld.range_count == 0 || covered == 3 * ld.triangle_count);
    if (l == 0) CHECK(ld.attribute_count == 1 && ld.range_count == 2 && ld.source_vertex[5] == 5);
  }
  stream.kind = SLOD_ATTRIBUTE_GENERIC;
  CHECK(slod_chain_build(ctx, &md, &chd, &chain) == SLOD_ERROR_UNSUPPORTED);
  CHECK(strstr(slod_last_error_message(ctx), "textured sphere: attributes[0] (GENERIC)") != NULL);
  free(uv);
  return 1;
}

/* Several views: two eyes in one group and a shadow cascade in another, on a context with room for
 * two groups; then the errors of bad views. Returns whether every check in it passed. */
static int checkViews(const slod_mesh_desc* md, const slod_chain_desc* chd) {
  const int before = failures;
  slod_context_desc cd;
  slod_context* vc = NULL;
  slod_chain ch = SLOD_NULL_CHAIN;
  slod_object_desc od;
  slod_object obj;
  slod_view views[9];
  slod_frame_params fp;
  slod_frame_result fr;
  slod_selection sel[16];
  int8_t levels[32];
  int i, shadow_drawn = 0;
  slod_context_desc_init(&cd);
  cd.max_objects = 16;
  cd.max_view_groups = 2;
  CHECK(slod_context_create(&cd, &vc) == SLOD_OK);
  CHECK(slod_chain_build(vc, md, chd, &ch) == SLOD_OK);
  for (i = 0; i < 16; ++i) {
    slod_object_desc_init(&od);
    od.chain = ch;
    od.translation[0] = 3.0f * (float)(i % 4) - 4.5f;
    od.translation[2] = -3.0f - 6.0f * (float)(i / 4);
    CHECK(slod_object_add(vc, &od, &obj) == SLOD_OK);
  }
  for (i = 0; i < 9; ++i) slod_view_init(&views[i]);
  for (i = 0; i < 2; ++i) {
    views[i].kind = SLOD_VIEW_EYE;
    views[i].eye[0] = views[i].target[0] = i ? 0.032f : -0.032f;
  }
  views[2].kind = SLOD_VIEW_SHADOW;
  views[2].group = 1;
  views[2].eye[0] = 0.0f; views[2].eye[1] = 50.0f; views[2].eye[2] = -10.0f;
  views[2].target[2] = -10.0f;
  views[2].up[1] = 0.0f; views[2].up[2] = -1.0f;
  views[2].ortho_height = 40.0f;
  views[2].near_plane = 1.0f;
  views[2].far_plane = 100.0f;
  views[2].viewport_width = views[2].viewport_height = 1024;
  views[2].pixels_per_cell = 0.25f; /* would want finer levels than the eyes */
  slod_frame_params_init(&fp);
  fp.budget_ms = 0.0f;
  slod_frame_result_init(&fr);
  CHECK(slod_select_views(vc, views, 3, &fp, sel, sizeof sel[0], 16, levels, 32, &fr) == SLOD_OK);
  CHECK(fr.group_count == 2);
  for (i = 0; i < 16; ++i) {
    CHECK(levels[i] == sel[i].level);
    if (levels[16 + i] >= 0) {
      CHECK(levels[i] >= 0 && levels[16 + i] >= levels[i]);
      ++shadow_drawn;
    }
  }
  CHECK(shadow_drawn > 0);
  /* bad input */
  CHECK(slod_select_views(vc, views, 9, &fp, sel, sizeof sel[0], 16, levels, 32, &fr) == SLOD_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(slod_last_error_message(vc), "view_count") != NULL);
  CHECK(slod_select_views(vc, views, 3, &fp, sel, sizeof sel[0], 16, levels, 16, &fr) == SLOD_ERROR_CAPACITY);
  views[2].group = 0;
  CHECK(slod_select_views(vc, views, 3, &fp, sel, sizeof sel[0], 16, levels, 32, &fr) == SLOD_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(slod_last_error_message(vc), "mixing kinds") != NULL);
  views[2].group = 1;
  views[2].viewport_width = 0;
  CHECK(slod_select_views(vc, views, 3, &fp, sel, sizeof sel[0], 16, levels, 32, &fr) == SLOD_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(slod_last_error_message(vc), "zero viewport") != NULL);
  views[2].viewport_width = 1024;
  views[1].kind = 7;
  CHECK(slod_select_views(vc, views, 3, &fp, sel, sizeof sel[0], 16, levels, 32, &fr) == SLOD_ERROR_INVALID_ARGUMENT);
  slod_context_destroy(vc);
  /* a context without room for view groups refuses views */
  cd.max_view_groups = 0;
  CHECK(slod_context_create(&cd, &vc) == SLOD_OK);
  CHECK(slod_chain_build(vc, md, chd, &ch) == SLOD_OK);
  slod_object_desc_init(&od);
  od.chain = ch;
  od.translation[2] = -3.0f;
  CHECK(slod_object_add(vc, &od, &obj) == SLOD_OK);
  views[1].kind = SLOD_VIEW_EYE;
  CHECK(slod_select_views(vc, views, 3, &fp, sel, sizeof sel[0], 16, levels, 32, &fr) == SLOD_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(slod_last_error_message(vc), "max_view_groups") != NULL);
  slod_context_destroy(vc);
  cd.max_view_groups = 9;
  CHECK(slod_context_create(&cd, &vc) == SLOD_ERROR_INVALID_ARGUMENT);
  return failures == before;
}

/* transitions: a camera jump starts a cross-fade of fade_ms at the caller's dt_ms; bad parameters
 * are refused with a message naming them */
static int checkTransitions(slod_context* ctx, const slod_camera* near_cam) {
  slod_selection sel[64];
  slod_frame_params fp;
  slod_frame_result fr;
  slod_camera far_cam = *near_cam;
  uint32_t i, n = slod_object_count(ctx);
  int frame, fading_frames = 0, object = -1;
  int32_t before = -2, far_level = -1, near_levels[64];
  slod_frame_params_init(&fp);
  fp.budget_ms = 0.0f;
  fp.transitions = SLOD_TRANSITIONS_FADE;
  fp.dt_ms = 20.0f;
  fp.fade_ms = 100.0f;
  slod_frame_result_init(&fr);
  far_cam.eye[2] += 40.0f;
  far_cam.target[2] += 40.0f;
  CHECK(slod_select(ctx, near_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_OK);
  for (i = 0; i < n; ++i) CHECK(sel[i].previous_level == sel[i].level && sel[i].fade == 1.0f && sel[i].morph == 0.0f);
  CHECK(slod_select(ctx, near_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_OK);
  for (i = 0; i < n; ++i) near_levels[i] = sel[i].level;
  for (frame = 0; frame < 20; ++frame) {
    CHECK(slod_select(ctx, &far_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_OK);
    if (frame == 0)
      for (i = 0; i < n && object < 0; ++i)
        if (sel[i].level >= 0 && near_levels[i] >= 0 && sel[i].level != near_levels[i]) {
          object = (int)i;
          before = near_levels[i];
        }
    if (object < 0) break;
    if (sel[object].previous_level != sel[object].level) {
      CHECK(sel[object].previous_level == before);
      CHECK(fabsf(sel[object].fade - 0.2f * (float)fading_frames) < 1e-5f);
      ++fading_frames;
    }
  }
  CHECK(object >= 0);
  far_level = object >= 0 ? sel[object].level : -1;
  CHECK(sel[object].level != before);
  CHECK(fading_frames == 5); /* 100 ms at 20 ms a frame */
  fp.dt_ms = -1.0f;
  CHECK(slod_select(ctx, near_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(slod_last_error_message(ctx), "dt_ms") != NULL);
  fp.dt_ms = 16.0f;
  fp.morph_band = 0.0f;
  CHECK(slod_select(ctx, near_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(slod_last_error_message(ctx), "morph_band") != NULL);
  fp.morph_band = 0.3f;
  fp.fade_ms = -5.0f;
  CHECK(slod_select(ctx, near_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(slod_last_error_message(ctx), "fade_ms") != NULL);
  fp.fade_ms = 250.0f;
  fp.transitions = 7;
  CHECK(slod_select(ctx, near_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(slod_last_error_message(ctx), "transitions") != NULL);
  /* morph mode on chains without morph data: selects, with fades */
  fp.transitions = SLOD_TRANSITIONS_MORPH;
  far_cam.eye[2] += 400.0f;
  far_cam.target[2] += 400.0f;
  CHECK(slod_select(ctx, &far_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_OK);
  CHECK(sel[object].level != far_level && sel[object].morph == 0.0f);
  CHECK(sel[object].previous_level == far_level && sel[object].fade == 0.0f);
  /* the drop policy: a budget below the per-frame constant keeps the large objects in view (over
   * budget) unless min_drop_px is 0, which drops them all */
  fp.transitions = SLOD_TRANSITIONS_NONE;
  fp.budget_ms = 0.001f;
  fp.min_drop_px = 4.0f;
  CHECK(slod_select(ctx, near_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_OK);
  CHECK(fr.drawn_count > 0 && fr.over_budget);
  fp.min_drop_px = 0.0f;
  CHECK(slod_select(ctx, near_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_OK);
  CHECK(fr.drawn_count == 0 && fr.dropped_count > 0);
  fp.min_drop_px = -1.0f;
  CHECK(slod_select(ctx, near_cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_ERROR_INVALID_ARGUMENT);
  CHECK(strstr(slod_last_error_message(ctx), "min_drop_px") != NULL);
  fp.min_drop_px = 4.0f;
  return 1;
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
  slod_chain chain = SLOD_NULL_CHAIN, levels_chain = SLOD_NULL_CHAIN;
  uint32_t levels, l;
  int i, frame;
  float saved_y;
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
  CHECK(slod_select(NULL, NULL, NULL, NULL, 0, 0, NULL) == SLOD_ERROR_INVALID_ARGUMENT);

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
  CHECK(chain != SLOD_NULL_CHAIN);
  levels = slod_chain_level_count(ctx, chain);
  CHECK(levels == 6);
  slod_level_data_init(&ld);
  for (l = 0; l < levels; ++l) {
    CHECK(slod_level_get(ctx, chain, l, &ld) == SLOD_OK);
    CHECK(ld.vertex_count > 0 && ld.positions != NULL);
    if (l == 0) CHECK(ld.triangle_count == index_count / 3 && ld.cell_width == 0.0f);
    if (l > 0) CHECK(ld.cell_width > 0.0f);
  }
  CHECK(slod_level_get(ctx, chain, levels, &ld) == SLOD_ERROR_NOT_FOUND);
  CHECK(strstr(slod_last_error_message(ctx), "levels") != NULL);

  /* bad chain descriptors are refused with a message: an int outside the method enum, a denormal
   * first cell width (both found by the capi fuzz target) */
  {
    slod_chain_desc bad = chd;
    int unknown = 4;
    memcpy(&bad.method, &unknown, sizeof unknown);
    CHECK(slod_chain_build(ctx, &md, &bad, &levels_chain) == SLOD_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(slod_last_error_message(ctx), "unknown method 4") != NULL);
    bad = chd;
    bad.first_cell_width = 1e-43f;
    CHECK(slod_chain_build(ctx, &md, &bad, &levels_chain) == SLOD_ERROR_INVALID_ARGUMENT);
    CHECK(strstr(slod_last_error_message(ctx), "first_cell_width") != NULL);
  }

  /* bad meshes are refused with a message */
  indices[5] = 100000;
  CHECK(slod_chain_build(ctx, &md, &chd, &levels_chain) == SLOD_ERROR_INVALID_MESH);
  CHECK(strstr(slod_last_error_message(ctx), "sphere") != NULL);
  indices[5] = 0;
  saved_y = positions[4];
  positions[4] = NAN;
  CHECK(slod_chain_build(ctx, &md, &chd, &levels_chain) == SLOD_ERROR_INVALID_MESH);
  CHECK(slod_chain_load_file(ctx, "/nonexistent/model.glb", &chd, &levels_chain) == SLOD_ERROR_IO);
  positions[4] = saved_y;
  CHECK(slod_chain_count(ctx) == 1);
  CHECK(callback_calls >= 4);

  /* objects on a line along -z */
  for (i = 0; i < 40; ++i) {
    slod_object_desc_init(&od);
    od.chain = chain;
    od.translation[2] = -3.0f * (float)i;
    od.user_data = (uint64_t)(1000 + i);
    CHECK(slod_object_add(ctx, &od, &objects[i]) == SLOD_OK);
  }
  CHECK(slod_object_count(ctx) == 40);
  od.chain = chain + ((slod_chain)1 << 32); /* the right slot, a wrong generation */
  CHECK(slod_object_add(ctx, &od, &objects[40]) == SLOD_ERROR_NOT_FOUND);
  od.chain = chain;
  od.scale = -1.0f;
  CHECK(slod_object_add(ctx, &od, &objects[40]) == SLOD_ERROR_INVALID_ARGUMENT);

  slod_camera_init(&cam);
  cam.eye[2] = 4.0f;
  cam.target[2] = -10.0f;
  slod_frame_params_init(&fp);
  fp.budget_ms = 0.0f; /* distance mode */
  slod_frame_result_init(&fr);
  CHECK(slod_select(ctx, &cam, &fp, sel, sizeof(slod_selection), 10, &fr) == SLOD_ERROR_CAPACITY);
  CHECK(slod_select(ctx, &cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_OK);
  for (i = 0; i < 40; ++i) {
    CHECK(sel[i].level >= -1 && sel[i].level < (int32_t)levels);
    CHECK(sel[i].user_data == (uint64_t)(1000 + i));
  }
  /* farther objects never get finer levels in distance mode */
  for (i = 1; i < 40; ++i)
    if (sel[i].level >= 0 && sel[i - 1].level >= 0) CHECK(sel[i].level >= sel[i - 1].level);
  CHECK(sel[0].level >= 0);

  /* picking hits the nearest object at its drawn level */
  slod_pick_result_init(&pr);
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
    CHECK(slod_select(ctx, &cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_OK);
    CHECK(fr.over_budget || fr.predicted_ms <= fp.budget_ms * 1.0001f);
    CHECK(slod_report_frame_time(ctx, fr.frame, 1.5f) == SLOD_OK);
  }
  CHECK(slod_chain_destroy(ctx, chain) == SLOD_ERROR_UNSUPPORTED);
  CHECK(slod_record_stop(ctx) == SLOD_OK);
  CHECK(slod_record_stop(ctx) == SLOD_ERROR_UNSUPPORTED);

  /* removal makes the handle stale */
  CHECK(slod_object_remove(ctx, objects[3]) == SLOD_OK);
  CHECK(slod_object_remove(ctx, objects[3]) == SLOD_ERROR_NOT_FOUND);
  CHECK(slod_object_set_importance(ctx, objects[3], 2.0f) == SLOD_ERROR_NOT_FOUND);
  CHECK(slod_object_set_importance(ctx, objects[4], 2.0f) == SLOD_OK);
  CHECK(slod_object_count(ctx) == 39);
  CHECK(slod_select(ctx, &cam, &fp, sel, sizeof(slod_selection), 64, &fr) == SLOD_OK);
  for (i = 0; i < 39; ++i) CHECK(sel[i].object != objects[3]);

  CHECK(checkTransitions(ctx, &cam));
  CHECK(checkChainLifecycle(ctx, chain, &md, &cam, &fp, objects[0]));
  CHECK(checkAttributes(ctx, &md));
  CHECK(checkViews(&md, &chd));

  slod_context_destroy(ctx);
  free(positions);
  free(indices);
  return finish("capi_test");
}
