/* The size-tagged structs from a C99 program: structs of another version than the library's.
 * An "old caller" declares each struct as it would have been before its last fields were appended
 * (the current struct without them) and sets size to that sizeof: the library must default the
 * missing fields, read nothing past the struct and write nothing past it. A newer caller's longer
 * struct is read as far as the library knows it. A size of 0 (no _init) or one that does not cover
 * the first field is refused with a message naming the struct. Exits non-zero when a check failed,
 * with a message per failed check. */
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include "scenelod/scenelod.h"
#include "test_support.h"

/* the structs as an older header declared them */
typedef struct old_context_desc { uint32_t size; size_t max_objects; } old_context_desc;
typedef struct old_mesh_desc {
  uint32_t size;
  const float* positions;
  size_t vertex_count, position_stride;
  const uint32_t* indices;
  size_t index_count;
} old_mesh_desc;
typedef struct old_chain_desc { uint32_t size; slod_method method; uint32_t level_count; } old_chain_desc;
typedef struct old_object_desc {
  uint32_t size;
  slod_chain chain;
  float translation[3], rotation[4], scale;
} old_object_desc;
typedef struct old_camera { uint32_t size; float eye[3], target[3], up[3]; } old_camera;
typedef struct old_frame_params { uint32_t size; float budget_ms; } old_frame_params;
typedef struct old_level_data { uint32_t size; float cell_width, max_error; uint32_t vertex_count, triangle_count; } old_level_data;
typedef struct old_frame_result { uint32_t size; uint64_t frame; float predicted_ms; } old_frame_result;
typedef struct old_pick_result { uint32_t size; slod_object object; int32_t level; } old_pick_result;
typedef struct old_selection { slod_object object; uint64_t user_data; } old_selection;

/* the 1.0 header's mesh and level structs: everything before the fields 1.1 appended (attributes) */
typedef struct v10_mesh_desc {
  old_mesh_desc old; /* the oldest caller's fields */
  const char* name;
} v10_mesh_desc;
typedef struct v10_level_data {
  uint32_t size;
  float cell_width, max_error;
  uint32_t vertex_count, triangle_count, edge_count, point_count;
  const float *positions, *normals;
  const uint32_t *triangles, *edges;
  const float* edge_thickness;
  const uint32_t* points;
} v10_level_data;

/* a newer header's versions: one more field each */
typedef struct new_object_desc { slod_object_desc d; double future; } new_object_desc;
typedef struct new_selection { slod_selection s; uint64_t future; } new_selection;
/* the 1.1 header's selection and frame params: before the transition fields */
typedef struct v11_selection { slod_object object; uint64_t user_data; int32_t level; } v11_selection;
typedef struct v11_frame_params { uint32_t size; float budget_ms, pixels_per_cell; } v11_frame_params;

#define GUARD 0xab
#define OBJECTS 24

/* each old struct followed by bytes the library must neither read (0xff: a NaN float, an all-ones
 * pointer) nor write (GUARD) */
static struct { old_context_desc v; unsigned char tail[64]; } context_in;
static struct { old_mesh_desc v; unsigned char tail[64]; } mesh_in;
static struct { old_chain_desc v; unsigned char tail[64]; } chain_in;
static struct { old_object_desc v; unsigned char tail[64]; } object_in;
static struct { old_camera v; unsigned char tail[64]; } camera_in;
static struct { old_frame_params v; unsigned char tail[64]; } params_in;
static struct { old_level_data v; unsigned char tail[64]; } level_out;
static struct { v10_mesh_desc v; unsigned char tail[64]; } v10_mesh_in;
static struct { v10_level_data v; unsigned char tail[64]; } v10_level_out;
static struct { old_frame_result v; unsigned char tail[64]; } result_out;
static struct { old_pick_result v; unsigned char tail[64]; } pick_out;
static struct { old_selection v[OBJECTS]; unsigned char tail[64]; } selection_out;
static new_selection newer_out[OBJECTS];
static struct { v11_selection v[OBJECTS]; unsigned char tail[64]; } v11_out;
static struct { v11_frame_params v; unsigned char tail[64]; } v11_params_in;

static int untouched(const unsigned char* p, size_t n) {
  size_t i;
  for (i = 0; i < n; ++i)
    if (p[i] != GUARD) return 0;
  return 1;
}

static int mentions(const slod_context* ctx, const char* what) { return strstr(slod_last_error_message(ctx), what) != NULL; }

/* a context, a chain and OBJECTS objects on a line, all through old structs */
static slod_context* oldCallerScene(const float* positions, size_t vertex_count, const uint32_t* indices,
                                    size_t index_count, slod_chain* chain, slod_object* objects) {
  slod_context* ctx = NULL;
  int i;
  memset(&context_in, 0xff, sizeof context_in);
  context_in.v.size = sizeof(old_context_desc);
  context_in.v.max_objects = OBJECTS + 1;
  CHECK(slod_context_create((const slod_context_desc*)&context_in, &ctx) == SLOD_OK);
  if (!ctx) return NULL;

  memset(&mesh_in, 0xff, sizeof mesh_in);
  mesh_in.v.size = sizeof(old_mesh_desc);
  mesh_in.v.positions = positions;
  mesh_in.v.vertex_count = vertex_count;
  mesh_in.v.position_stride = 0;
  mesh_in.v.indices = indices;
  mesh_in.v.index_count = index_count;
  memset(&chain_in, 0xff, sizeof chain_in);
  chain_in.v.size = sizeof(old_chain_desc);
  chain_in.v.method = SLOD_METHOD_FLOATING;
  chain_in.v.level_count = 4;
  CHECK(slod_chain_build(ctx, (const slod_mesh_desc*)&mesh_in, (const slod_chain_desc*)&chain_in, chain) == SLOD_OK);
  CHECK(slod_chain_level_count(ctx, *chain) == 5); /* first_cell_width defaulted to automatic */

  for (i = 0; i < OBJECTS; ++i) {
    memset(&object_in, 0xff, sizeof object_in);
    object_in.v.size = sizeof(old_object_desc);
    object_in.v.chain = *chain;
    object_in.v.translation[0] = 0.0f;
    object_in.v.translation[1] = 0.0f;
    object_in.v.translation[2] = -3.0f * (float)i;
    object_in.v.rotation[0] = object_in.v.rotation[1] = object_in.v.rotation[2] = 0.0f;
    object_in.v.rotation[3] = 1.0f;
    object_in.v.scale = 1.0f; /* importance, must_draw and user_data default to 1, 0, 0 */
    CHECK(slod_object_add(ctx, (const slod_object_desc*)&object_in, &objects[i]) == SLOD_OK);
  }
  return ctx;
}

/* old inputs select as the current structs with their defaults do; old outputs land at the
 * caller's size and stride and nothing past them is written */
static void checkOldCaller(slod_context* ctx, slod_chain chain, const slod_object* objects) {
  slod_camera cam;
  slod_frame_params fp;
  slod_frame_result fr;
  slod_selection full[OBJECTS];
  slod_level_data ld;
  slod_pick_result pr;
  int i;

  slod_camera_init(&cam); /* eye (0, 0, 5) toward the origin, 60 degrees, 1280 x 720 */
  slod_frame_params_init(&fp);
  fp.budget_ms = 0.0f;
  slod_frame_result_init(&fr);
  CHECK(slod_select(ctx, &cam, &fp, full, sizeof(slod_selection), OBJECTS, &fr) == SLOD_OK);
  for (i = 0; i < OBJECTS; ++i) CHECK(full[i].object == objects[i] && full[i].user_data == 0);
  CHECK(full[0].level >= 0);

  memset(&camera_in, 0xff, sizeof camera_in);
  camera_in.v.size = sizeof(old_camera);
  memcpy(camera_in.v.eye, cam.eye, sizeof cam.eye);
  memcpy(camera_in.v.target, cam.target, sizeof cam.target);
  memcpy(camera_in.v.up, cam.up, sizeof cam.up);
  memset(&params_in, 0xff, sizeof params_in);
  params_in.v.size = sizeof(old_frame_params);
  params_in.v.budget_ms = 0.0f;
  memset(&result_out, GUARD, sizeof result_out);
  result_out.v.size = sizeof(old_frame_result);
  memset(&selection_out, GUARD, sizeof selection_out);
  CHECK(slod_select(ctx, (const slod_camera*)&camera_in, (const slod_frame_params*)&params_in, selection_out.v,
                    sizeof(old_selection), OBJECTS, (slod_frame_result*)&result_out) == SLOD_OK);
  for (i = 0; i < OBJECTS; ++i) CHECK(selection_out.v[i].object == objects[i] && selection_out.v[i].user_data == 0);
  CHECK(untouched(selection_out.tail, sizeof selection_out.tail));
  CHECK(result_out.v.size == sizeof(old_frame_result) && result_out.v.frame == fr.frame + 1);
  CHECK(untouched(result_out.tail, sizeof result_out.tail));

  /* a 1.1 caller: no transition fields in its params (defaults: none) nor in its selections */
  memset(&v11_params_in, 0xff, sizeof v11_params_in);
  v11_params_in.v.size = sizeof(v11_frame_params);
  v11_params_in.v.budget_ms = 0.0f;
  v11_params_in.v.pixels_per_cell = 1.0f;
  memset(&v11_out, GUARD, sizeof v11_out);
  CHECK(slod_select(ctx, &cam, (const slod_frame_params*)&v11_params_in, v11_out.v, sizeof(v11_selection), OBJECTS,
                    NULL) == SLOD_OK);
  for (i = 0; i < OBJECTS; ++i) CHECK(v11_out.v[i].object == objects[i] && v11_out.v[i].level == full[i].level);
  CHECK(untouched(v11_out.tail, sizeof v11_out.tail));

  /* the same frame again, through the old structs' defaults: the same levels */
  CHECK(slod_select(ctx, &cam, &fp, newer_out, sizeof(new_selection), OBJECTS, NULL) == SLOD_OK);
  for (i = 0; i < OBJECTS; ++i) CHECK(newer_out[i].s.level == full[i].level && newer_out[i].s.object == objects[i]);

  memset(&level_out, GUARD, sizeof level_out);
  level_out.v.size = sizeof(old_level_data);
  slod_level_data_init(&ld);
  CHECK(slod_level_get(ctx, chain, 1, (slod_level_data*)&level_out) == SLOD_OK);
  CHECK(slod_level_get(ctx, chain, 1, &ld) == SLOD_OK);
  CHECK(level_out.v.size == sizeof(old_level_data) && level_out.v.cell_width == ld.cell_width &&
        level_out.v.triangle_count == ld.triangle_count && level_out.v.triangle_count > 0);
  CHECK(untouched(level_out.tail, sizeof level_out.tail));

  memset(&pick_out, GUARD, sizeof pick_out);
  pick_out.v.size = sizeof(old_pick_result);
  slod_pick_result_init(&pr);
  CHECK(slod_pick(ctx, &cam, 640.0f, 360.0f, &pr) == SLOD_OK && pr.object == objects[0]);
  CHECK(slod_pick(ctx, (const slod_camera*)&camera_in, 640.0f, 360.0f, (slod_pick_result*)&pick_out) == SLOD_OK);
  CHECK(pick_out.v.object == objects[0] && pick_out.v.level == pr.level);
  CHECK(untouched(pick_out.tail, sizeof pick_out.tail));
}

/* a 1.0 caller (no attribute fields; the bytes after its structs all ones) builds a chain without
 * attributes and reads its levels without anything written past its level struct */
static void checkVersion10Caller(slod_context* ctx, size_t vertex_count) {
  slod_chain_desc cd;
  slod_chain chain = SLOD_NULL_CHAIN;
  slod_level_data ld;
  CHECK(sizeof(v10_mesh_desc) == offsetof(slod_mesh_desc, attributes));
  CHECK(sizeof(v10_level_data) == offsetof(slod_level_data, attribute_count));
  memset(&v10_mesh_in, 0xff, sizeof v10_mesh_in);
  v10_mesh_in.v.old = mesh_in.v; /* oldCallerScene's mesh */
  v10_mesh_in.v.old.size = sizeof(v10_mesh_desc);
  v10_mesh_in.v.name = "1.0 sphere";
  slod_chain_desc_init(&cd);
  cd.level_count = 2;
  CHECK(slod_chain_build(ctx, (const slod_mesh_desc*)&v10_mesh_in, &cd, &chain) == SLOD_OK);
  memset(&v10_level_out, GUARD, sizeof v10_level_out);
  v10_level_out.v.size = sizeof(v10_level_data);
  CHECK(slod_level_get(ctx, chain, 0, (slod_level_data*)&v10_level_out) == SLOD_OK);
  CHECK(v10_level_out.v.vertex_count == vertex_count && v10_level_out.v.positions != NULL);
  CHECK(untouched(v10_level_out.tail, sizeof v10_level_out.tail));
  /* the same level through the current struct: no streams, ranges or skin were read from the tail */
  slod_level_data_init(&ld);
  CHECK(slod_level_get(ctx, chain, 0, &ld) == SLOD_OK);
  CHECK(ld.attribute_count == 0 && ld.range_count == 0 && ld.ranges == NULL && ld.joints == NULL && ld.joint_count == 0);
  CHECK(ld.source_vertex != NULL && ld.source_vertex[vertex_count - 1] == vertex_count - 1);
  CHECK(slod_chain_destroy(ctx, chain) == SLOD_OK);
}

/* a newer caller's longer structs: the fields past the library's are ignored on input and left
 * alone on output */
static void checkNewerCaller(slod_context* ctx, slod_chain chain) {
  new_object_desc od;
  slod_object extra;
  slod_camera cam;
  slod_frame_params fp;
  int i;
  slod_object_desc_init(&od.d);
  od.d.size = sizeof od;
  od.d.chain = chain;
  od.d.user_data = 77;
  od.future = 1.0e300;
  CHECK(slod_object_add(ctx, &od.d, &extra) == SLOD_OK);
  slod_camera_init(&cam);
  slod_frame_params_init(&fp);
  memset(newer_out, GUARD, sizeof newer_out);
  CHECK(slod_select(ctx, &cam, &fp, newer_out, sizeof(new_selection), OBJECTS, NULL) == SLOD_ERROR_CAPACITY);
  CHECK(slod_object_remove(ctx, extra) == SLOD_OK);
  CHECK(slod_select(ctx, &cam, &fp, newer_out, sizeof(new_selection), OBJECTS, NULL) == SLOD_OK);
  for (i = 0; i < OBJECTS; ++i) CHECK(untouched((const unsigned char*)&newer_out[i].future, sizeof newer_out[i].future));
}

/* sizes that do not cover the first field are refused, naming the struct */
static void checkRefused(slod_context* ctx, slod_chain chain) {
  slod_context_desc cd;
  slod_context* none = NULL;
  slod_mesh_desc md;
  slod_chain_desc chd;
  slod_chain c;
  slod_object_desc od;
  slod_object o;
  slod_camera cam;
  slod_frame_params fp;
  slod_frame_result fr;
  slod_level_data ld;
  slod_pick_result pr;
  slod_attribute_stream as;
  slod_selection sel[OBJECTS];

  slod_context_desc_init(&cd);
  cd.size = 0;
  CHECK(slod_context_create(&cd, &none) == SLOD_ERROR_INVALID_ARGUMENT && none == NULL);
  CHECK(slod_last_error(NULL) == SLOD_ERROR_INVALID_ARGUMENT && mentions(NULL, "slod_context_desc.size is 0"));
  cd.size = 8; /* covers size and padding, not max_objects */
  CHECK(slod_context_create(&cd, &none) == SLOD_ERROR_INVALID_ARGUMENT && mentions(NULL, "slod_context_desc_init"));

  slod_mesh_desc_init(&md);
  slod_chain_desc_init(&chd);
  md.size = 0;
  CHECK(slod_chain_build(ctx, &md, &chd, &c) == SLOD_ERROR_INVALID_ARGUMENT && mentions(ctx, "slod_mesh_desc"));
  slod_mesh_desc_init(&md);
  chd.size = 4;
  CHECK(slod_chain_build(ctx, &md, &chd, &c) == SLOD_ERROR_INVALID_ARGUMENT && mentions(ctx, "slod_chain_desc"));
  CHECK(slod_chain_load_file(ctx, "x.obj", &chd, &c) == SLOD_ERROR_INVALID_ARGUMENT && mentions(ctx, "slod_chain_desc"));

  slod_object_desc_init(&od);
  od.chain = chain;
  od.size = 0;
  CHECK(slod_object_add(ctx, &od, &o) == SLOD_ERROR_INVALID_ARGUMENT && mentions(ctx, "slod_object_desc.size is 0"));

  slod_camera_init(&cam);
  slod_frame_params_init(&fp);
  slod_frame_result_init(&fr);
  cam.size = 0;
  CHECK(slod_select(ctx, &cam, &fp, sel, sizeof sel[0], OBJECTS, &fr) == SLOD_ERROR_INVALID_ARGUMENT && mentions(ctx, "slod_camera"));
  slod_camera_init(&cam);
  fp.size = 0;
  CHECK(slod_select(ctx, &cam, &fp, sel, sizeof sel[0], OBJECTS, &fr) == SLOD_ERROR_INVALID_ARGUMENT &&
        mentions(ctx, "slod_frame_params"));
  slod_frame_params_init(&fp);
  fr.size = 0;
  CHECK(slod_select(ctx, &cam, &fp, sel, sizeof sel[0], OBJECTS, &fr) == SLOD_ERROR_INVALID_ARGUMENT &&
        mentions(ctx, "slod_frame_result"));
  CHECK(slod_select(ctx, &cam, &fp, sel, 0, OBJECTS, NULL) == SLOD_ERROR_INVALID_ARGUMENT && mentions(ctx, "out_stride"));

  slod_level_data_init(&ld);
  ld.size = 0;
  CHECK(slod_level_get(ctx, chain, 0, &ld) == SLOD_ERROR_INVALID_ARGUMENT && mentions(ctx, "slod_level_data"));
  slod_pick_result_init(&pr);
  pr.size = 0;
  CHECK(slod_pick(ctx, &cam, 1.0f, 1.0f, &pr) == SLOD_ERROR_INVALID_ARGUMENT && mentions(ctx, "slod_pick_result"));
  slod_attribute_stream_init(&as);
  as.size = 4;
  CHECK(slod_level_attribute_get(ctx, chain, 0, 0, &as) == SLOD_ERROR_INVALID_ARGUMENT && mentions(ctx, "slod_attribute_stream"));
}

int main(void) {
  float* positions;
  uint32_t* indices;
  size_t vertex_count, index_count;
  slod_chain chain = SLOD_NULL_CHAIN;
  slod_object objects[OBJECTS];
  slod_context* ctx;

  makeSphere(24, 48, &positions, &vertex_count, &indices, &index_count);
  ctx = oldCallerScene(positions, vertex_count, indices, index_count, &chain, objects);
  if (ctx) {
    checkOldCaller(ctx, chain, objects);
    checkNewerCaller(ctx, chain);
    checkRefused(ctx, chain);
    checkVersion10Caller(ctx, vertex_count);
  }
  slod_context_destroy(ctx);
  free(positions);
  free(indices);
  return finish("old_caller_test");
}
