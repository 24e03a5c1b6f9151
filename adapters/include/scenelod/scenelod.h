/* scenelod C API (C99).
 *
 * A stable way into scenelod for engines that are not C++ or not built with the same compiler:
 * opaque handles, status codes, size-tagged argument structs, no C++ exception crosses this boundary.
 *
 * Typical frame loop:
 *   slod_context_desc cd; slod_context_desc_init(&cd); cd.max_objects = 5000;
 *   slod_context* ctx; slod_context_create(&cd, &ctx);
 *   slod_chain_build(ctx, &mesh, &chain_desc, &chain);          (once per unique mesh)
 *   slod_object_add(ctx, &object_desc, &object);                 (once per instance)
 *   each frame: slod_object_set_trs(...) for what moved;
 *               slod_select(ctx, &camera, &params, out, sizeof(slod_selection), n, &result);
 *               draw out[i].level of out[i].object; slod_report_frame_time(ctx, result.frame, ms);
 *
 * Threads: a context is used by one thread at a time, except slod_report_frame_time, which may be
 * called from one other thread (the render thread) while slod_select runs. Different contexts are
 * independent. Each function's comment repeats what applies.
 *
 * ABI policy: libscenelod.so.MAJOR exports only slod_ symbols. Within a major version functions and
 * enum values are only added and struct fields only appended, so a binary built against an older
 * minor version keeps working with a newer library:
 * - every struct the caller passes in or out starts with `uint32_t size`, set to the caller's sizeof
 *   by its *_init function (static inline below, so it is compiled into the caller). The library reads
 *   and writes only the first min(size, its own sizeof) bytes: fields an older caller does not know
 *   get their defaults on input and are not written on output; the size field is never changed.
 *   A size that does not cover the struct's first field after `size` (0: the struct never went
 *   through *_init) is refused with SLOD_ERROR_INVALID_ARGUMENT and a message naming the struct;
 * - arrays of structs the library writes (slod_select's output) come with their element stride in
 *   bytes (the caller's sizeof); the library writes only min(stride, its own sizeof) bytes per element;
 * - arrays of size-tagged structs the caller passes (slod_mesh_desc.attributes) are stepped by their
 *   elements' size, which must be the same for all; each element is read as a single struct is;
 * - slod_allocator (nested in slod_context_desc) and slod_index_range never grow.
 * A binary built against a newer header needs a library at least as new (as for any shared library).
 * docs/INTEGRATION.md ("Migration") lists what changed between versions. */
#ifndef SCENELOD_SCENELOD_H
#define SCENELOD_SCENELOD_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(SCENELOD_CAPI_BUILD)
#define SLOD_API __attribute__((visibility("default")))
#else
#define SLOD_API
#endif

/* the library's version; the major version is the SONAME's (libscenelod.so.1) */
#define SLOD_VERSION_MAJOR 1
#define SLOD_VERSION_MINOR 2
#define SLOD_VERSION_PATCH 0

typedef enum slod_status {
  SLOD_OK = 0,
  SLOD_ERROR_INVALID_ARGUMENT = 1, /* null pointer, value out of range, struct size too small */
  SLOD_ERROR_INVALID_MESH = 2,     /* NaN coordinate, index out of range */
  SLOD_ERROR_IO = 3,               /* missing or unwritable file */
  SLOD_ERROR_PARSE = 4,            /* malformed file */
  SLOD_ERROR_UNSUPPORTED = 5,
  SLOD_ERROR_CORRUPT = 6,          /* truncated or damaged binary data */
  SLOD_ERROR_OUT_OF_MEMORY = 7,
  SLOD_ERROR_NOT_FOUND = 8,        /* stale or unknown object or chain handle */
  SLOD_ERROR_CAPACITY = 9,         /* more objects than max_objects, output array too small */
  SLOD_ERROR_UNKNOWN = 10,
  SLOD_ERROR_IN_USE = 11           /* a chain that objects still use */
} slod_status;

typedef struct slod_context slod_context;

/* An object handle: slot and generation; a removed object's handle is refused, never reused. */
typedef uint64_t slod_object;
#define SLOD_NULL_OBJECT ((slod_object)0)

/* A chain handle: slot and generation, as for objects; a destroyed chain's handle is refused. */
typedef uint64_t slod_chain;
#define SLOD_NULL_CHAIN ((slod_chain)0)

typedef struct slod_allocator {
  void* (*allocate)(void* user, size_t bytes, size_t alignment); /* null = the C library's */
  void (*free)(void* user, void* pointer);
  void* user;
} slod_allocator;

/* Called with every error a function returns, with its message (valid during the call). */
typedef void (*slod_error_callback)(void* user, slod_status status, const char* message);

typedef struct slod_context_desc {
  uint32_t size;                   /* sizeof(slod_context_desc), set by slod_context_desc_init */
  size_t max_objects;              /* objects the context can hold, > 0 (default 1024) */
  slod_allocator allocator;        /* memory of the per-frame selector state (default: C library) */
  slod_error_callback error_callback; /* optional */
  void* error_user;
  uint32_t max_view_groups;        /* view groups slod_select_views may use, 0..8 (default 0: none,
                                      and no memory for them; each costs about 285 bytes per object) */
} slod_context_desc;

static inline void slod_context_desc_init(slod_context_desc* desc) {
  if (!desc) return;
  memset(desc, 0, sizeof *desc);
  desc->size = (uint32_t)sizeof *desc;
  desc->max_objects = 1024;
}
/* Creates a context. Thread-safe (contexts are independent). On failure *out is null and the message
 * is kept for this thread (slod_last_error_message(NULL)); the error callback is not called. */
SLOD_API slod_status slod_context_create(const slod_context_desc* desc, slod_context** out);
/* Destroys a context and everything in it. Null is ignored. */
SLOD_API void slod_context_destroy(slod_context* ctx);
/* The status and message of the last failing call on this context (SLOD_OK and "" when none). With
 * a null ctx: those of the last failing slod_context_create on the calling thread. */
SLOD_API slod_status slod_last_error(const slod_context* ctx);
SLOD_API const char* slod_last_error_message(const slod_context* ctx);
SLOD_API const char* slod_status_name(slod_status status);
/* "scenelod MAJOR.MINOR.PATCH" of the library (which may be newer than the header). */
SLOD_API const char* slod_version_string(void);

/* ---- LOD chains ---- */

typedef enum slod_method {
  SLOD_METHOD_FLOATING = 0,   /* Low & Tan floating cells with the measured defaults */
  SLOD_METHOD_UNIFORM = 1,    /* Rossignac & Borrel uniform grid */
  SLOD_METHOD_ZHANG = 2,      /* vision-characteristic edge collapse */
  SLOD_METHOD_SCROOGE = 3     /* SCROOGE perceptual reduction */
} slod_method;

/* The kind of a vertex attribute stream; every stream holds floats. */
typedef enum slod_attribute_kind {
  SLOD_ATTRIBUTE_UV = 0,       /* texture coordinates, 2 per vertex; set 0, 1, ... (glTF TEXCOORD_n) */
  SLOD_ATTRIBUTE_COLOR = 1,    /* linear RGB, 3 per vertex, or 4 whose alpha is 1 (alpha is not carried) */
  SLOD_ATTRIBUTE_NORMAL = 2,   /* 3 per vertex */
  SLOD_ATTRIBUTE_TANGENT4 = 3, /* 4 per vertex: a unit tangent, w = +1 or -1 (the bitangent's sign) */
  SLOD_ATTRIBUTE_GENERIC = 4   /* not supported yet: refused with SLOD_ERROR_UNSUPPORTED. Carry such data
                                  through slod_level_data.source_vertex (copy each level vertex's value
                                  from its source vertex) */
} slod_attribute_kind;

/* One vertex attribute stream: as input in slod_mesh_desc.attributes (caller memory, copied), as
 * output from slod_level_attribute_get (library memory). */
typedef struct slod_attribute_stream {
  uint32_t size;               /* sizeof(slod_attribute_stream), set by slod_attribute_stream_init */
  slod_attribute_kind kind;
  uint32_t set;                /* the UV set (0 = TEXCOORD_0); 0 for the other kinds */
  uint32_t component_count;    /* floats per vertex (see slod_attribute_kind) */
  const float* data;
  size_t stride;               /* bytes between vertices; 0 = component_count floats */
  size_t count;                /* vertices data holds: at least vertex_count (output: the level's vertex_count) */
} slod_attribute_stream;

/* A run of triangles drawn with one material: an index range of slod_mesh_desc.indices on input, of
 * slod_level_data.triangles on output. This struct never grows. */
typedef struct slod_index_range {
  uint32_t first_index;        /* a multiple of 3 */
  uint32_t index_count;        /* a multiple of 3 */
  uint32_t material;           /* the caller's material id, returned untouched */
  uint32_t source_range;       /* output: the input range (index into slod_mesh_desc.ranges) these
                                  triangles come from; ignored on input */
} slod_index_range;

typedef struct slod_mesh_desc {
  uint32_t size;               /* sizeof(slod_mesh_desc), set by slod_mesh_desc_init */
  const float* positions;      /* 3 floats per vertex */
  size_t vertex_count;
  size_t position_stride;      /* bytes between vertices; 0 = 12 */
  const uint32_t* indices;     /* 3 per triangle */
  size_t index_count;
  const char* name;            /* for messages; may be null */
  /* since 1.1 (all optional; a 1.0 caller's struct ends above and gets none) */
  const slod_attribute_stream* attributes; /* an array of attribute_count streams, each filled by
                                  slod_attribute_stream_init (the library steps through it by their
                                  common size); at most one per kind and set, UV sets numbered 0, 1,
                                  ... without gaps */
  uint32_t attribute_count;
  uint32_t joint_count;        /* joints of the skeleton; > 0 when joints are given */
  const uint16_t* joints;      /* 4 joint indices per vertex (glTF JOINTS_0), each < joint_count */
  size_t joints_stride;        /* bytes; 0 = 8 */
  const float* weights;        /* 4 weights per vertex (WEIGHTS_0): finite, >= 0, summing to more than 0 */
  size_t weights_stride;       /* bytes; 0 = 16 */
  size_t skin_count;           /* vertices joints and weights hold: at least vertex_count */
  const int32_t* joint_parents;/* optional: joint_count entries, the parent joint or -1 (no cycles);
                                  lets the simplifiers tell neighbouring bones from unrelated limbs */
  const slod_index_range* ranges; /* optional: one per material or primitive, together covering
                                  every index once (no overlap, no gap) */
  uint32_t range_count;
} slod_mesh_desc;

typedef struct slod_chain_desc {
  uint32_t size;               /* sizeof(slod_chain_desc), set by slod_chain_desc_init */
  slod_method method;          /* default SLOD_METHOD_FLOATING */
  uint32_t level_count;        /* simplified levels after the original (default 8) */
  float first_cell_width;      /* object space; 0 = automatic (level 1 has about half the triangles) */
} slod_chain_desc;

static inline void slod_mesh_desc_init(slod_mesh_desc* desc) {
  if (!desc) return;
  memset(desc, 0, sizeof *desc);
  desc->size = (uint32_t)sizeof *desc;
}
static inline void slod_attribute_stream_init(slod_attribute_stream* stream) {
  if (!stream) return;
  memset(stream, 0, sizeof *stream);
  stream->size = (uint32_t)sizeof *stream;
  stream->kind = SLOD_ATTRIBUTE_UV;
}
static inline void slod_chain_desc_init(slod_chain_desc* desc) {
  if (!desc) return;
  memset(desc, 0, sizeof *desc);
  desc->size = (uint32_t)sizeof *desc;
  desc->method = SLOD_METHOD_FLOATING;
  desc->level_count = 8;
}
/* Builds a chain from caller memory (copied): positions and indices, and the mesh's attribute streams,
 * skin and index ranges when given (every level then carries them as far as its generator keeps
 * them; read them back with slod_level_get and slod_level_attribute_get). Writes its handle to
 * *out_chain. Errors name the mesh and the field or stream: a stream, skin array or range shorter
 * than or outside what it must cover, a NaN or infinite value, a joint >= joint_count, weights
 * summing to 0, overlapping ranges (SLOD_ERROR_INVALID_MESH); a GENERIC stream
 * (SLOD_ERROR_UNSUPPORTED). Not thread-safe on ctx. */
SLOD_API slod_status slod_chain_build(slod_context* ctx, const slod_mesh_desc* mesh, const slod_chain_desc* desc,
                                      slod_chain* out_chain);
/* Builds a chain from a file: OBJ, glTF or GLB (the whole file flattened into one mesh in world space).
 * Its levels' index ranges are the flattened mesh's triangle groups, its materials: material and
 * source_range are both the file's material index (0xffffffff for none). */
SLOD_API slod_status slod_chain_load_file(slod_context* ctx, const char* path, const slod_chain_desc* desc,
                                          slod_chain* out_chain);
/* Destroys a chain and frees its levels; its handle becomes stale, and so do the pointers
 * slod_level_get gave into it. Refused with SLOD_ERROR_IN_USE while objects use the chain (the
 * message names the chain and how many: remove them first), with SLOD_ERROR_UNSUPPORTED while
 * recording, with SLOD_ERROR_NOT_FOUND for a stale or unknown handle. Not thread-safe on ctx. */
SLOD_API slod_status slod_chain_destroy(slod_context* ctx, slod_chain chain);
/* Number of chains built and not destroyed. */
SLOD_API uint32_t slod_chain_count(const slod_context* ctx);
/* Number of levels of a chain (0 for a stale or unknown handle). */
SLOD_API uint32_t slod_chain_level_count(const slod_context* ctx, slod_chain chain);

typedef struct slod_level_data {
  uint32_t size;               /* sizeof(slod_level_data), set by slod_level_data_init */
  float cell_width;            /* object space; 0 for level 0 */
  float max_error;             /* measured maximum vertex displacement, object space */
  uint32_t vertex_count, triangle_count, edge_count, point_count;
  const float* positions;      /* 3 floats per vertex */
  const float* normals;        /* 3 floats per vertex, or null */
  const uint32_t* triangles;   /* 3 per triangle */
  const uint32_t* edges;       /* 2 per edge */
  const float* edge_thickness; /* 1 per edge (object space), or null */
  const uint32_t* points;      /* 1 per point */
  /* since 1.1 */
  uint32_t attribute_count;    /* streams: read stream i with slod_level_attribute_get */
  uint32_t range_count;        /* index ranges; 0 when the mesh had none or the level's generator did
                                  not keep them */
  const slod_index_range* ranges; /* range_count, in triangle order, one per input range that still
                                  has triangles in this level */
  const uint32_t* source_vertex; /* 1 per vertex: the vertex of level 0 (the input) whose attributes
                                  it mainly stands for; level 0: the identity. Null when the level's
                                  generator does not record it */
  const uint16_t* joints;      /* 4 per vertex, or null */
  const float* weights;        /* 4 per vertex, or null */
  uint32_t joint_count;        /* the input's joint_count */
  const int32_t* joint_parents;/* joint_count entries, or null when the input had none */
  /* since 1.2: geomorph targets (docs/INTEGRATION.md, "Geomorphs"). Per vertex of this level, its
     value in the next level: draw attribute a as a + f x (morph_a - a) for a morph factor f in [0, 1];
     at f = 1 the level matches the next one (exactly for nested chains). Null on the last level and
     where the chain's generator records none (SCROOGE); each attribute also null where the level has
     no such stream. A caller built against 1.1 passes a smaller size and never sees these. */
  const float* morph_positions;/* 3 per vertex */
  const float* morph_normals;  /* 3 per vertex */
  const float* morph_colors;   /* 3 per vertex (linear RGB) */
  const float* morph_uvs;      /* 2 per vertex, texture coordinate set 0 */
  const float* morph_tangents; /* 4 per vertex (w: the bitangent's sign, as the level's own) */
} slod_level_data;

static inline void slod_level_data_init(slod_level_data* data) {
  if (!data) return;
  memset(data, 0, sizeof *data);
  data->size = (uint32_t)sizeof *data;
}
/* Fills *out (its size set by slod_level_data_init) with a level's counts and pointers into the
 * context's memory (valid until the chain or the context is destroyed), for upload to the GPU. Not
 * thread-safe with chain building or destruction on the same ctx. */
SLOD_API slod_status slod_level_get(const slod_context* ctx, slod_chain chain, uint32_t level, slod_level_data* out);
/* Fills *out (its size set by slod_attribute_stream_init) with attribute stream `index` (below the
 * level's slod_level_data.attribute_count) of a level: its kind, set, component count and a pointer
 * into the context's memory (valid as slod_level_get's), stride = component_count floats, count = the
 * level's vertex count. Streams come in this order: NORMAL, COLOR (3 components), UV sets 0, 1, ...,
 * TANGENT4; each one the level has. Thread safety as slod_level_get. */
SLOD_API slod_status slod_level_attribute_get(const slod_context* ctx, slod_chain chain, uint32_t level, uint32_t index,
                                              slod_attribute_stream* out);

/* ---- objects ---- */

typedef struct slod_object_desc {
  uint32_t size;               /* sizeof(slod_object_desc), set by slod_object_desc_init */
  slod_chain chain;
  float translation[3];        /* world placement: T * R * S */
  float rotation[4];           /* unit quaternion x, y, z, w (default 0, 0, 0, 1) */
  float scale;                 /* uniform scale, > 0 (default 1) */
  float importance;            /* benefit weight, >= 0 (default 1) */
  int must_draw;               /* nonzero: always drawn, at least at the coarsest level */
  uint64_t user_data;          /* returned untouched in slod_selection */
} slod_object_desc;

static inline void slod_object_desc_init(slod_object_desc* desc) {
  if (!desc) return;
  memset(desc, 0, sizeof *desc);
  desc->size = (uint32_t)sizeof *desc;
  desc->rotation[3] = 1.0f;
  desc->scale = 1.0f;
  desc->importance = 1.0f;
}
/* Adds an object using a chain; writes its handle to *out. Refused while recording. */
SLOD_API slod_status slod_object_add(slod_context* ctx, const slod_object_desc* desc, slod_object* out);
/* Removes an object; its handle becomes stale. Refused while recording. */
SLOD_API slod_status slod_object_remove(slod_context* ctx, slod_object object);
/* Moves an object. O(1), no allocation (while not recording). */
SLOD_API slod_status slod_object_set_trs(slod_context* ctx, slod_object object, const float translation[3],
                                         const float rotation_xyzw[4], float scale);
SLOD_API slod_status slod_object_set_importance(slod_context* ctx, slod_object object, float importance);
SLOD_API uint32_t slod_object_count(const slod_context* ctx);

/* ---- per frame ---- */

typedef struct slod_camera {
  uint32_t size;               /* sizeof(slod_camera), set by slod_camera_init */
  float eye[3], target[3], up[3]; /* default eye (0, 0, 5), target (0, 0, 0), up (0, 1, 0) */
  float fov_y_deg;             /* default 60 */
  uint32_t viewport_width, viewport_height; /* pixels, default 1280 x 720 */
} slod_camera;

typedef struct slod_frame_params {
  uint32_t size;               /* sizeof(slod_frame_params), set by slod_frame_params_init */
  float budget_ms;             /* > 0: budget mode (Funkhouser & Sequin); <= 0: distance mode. Default 16.7 */
  float pixels_per_cell;       /* X: a level is accurate enough when a cell covers <= X pixels. Default 1 */
  /* level transitions (docs/SELECTION.md, "Transitions"; slod_select only, not slod_select_views) */
  int transitions;             /* slod_transitions, default SLOD_TRANSITIONS_NONE (hard switches) */
  float dt_ms;                 /* >= 0: time since the last slod_select, fades advance by it. Default 1000/60 */
  float fade_ms;               /* >= 0: a cross-fade's duration. Default 250 */
  float morph_band;            /* (0, 1]: share of a level's log pixel-size interval the morph takes. Default 0.3 */
  float fade_budget_share;     /* [0, 1], budget mode: share of the objects' budget fades may take. Default 0.1 */
  float min_drop_px;           /* >= 0, budget mode: objects in view with a projected radius of at least this many
                                  pixels (and not hidden) are never dropped, at worst drawn at their cheapest
                                  level (over_budget set when even that does not fit); 0: any may be. Default 4 */
} slod_frame_params;

typedef enum slod_transitions {
  SLOD_TRANSITIONS_NONE = 0,   /* hard switches: previous_level == level, fade 1, morph 0 */
  SLOD_TRANSITIONS_FADE = 1,   /* cross-fades over fade_ms: draw previous_level with weight 1 - fade too */
  SLOD_TRANSITIONS_MORPH = 2   /* geomorphs where levels have morph data, cross-fades elsewhere */
} slod_transitions;

/* One element of slod_select's output; the caller passes its sizeof as the stride. */
typedef struct slod_selection {
  slod_object object;
  uint64_t user_data;
  int32_t level;               /* level to draw, -1 = not drawn */
  /* transitions (slod_frame_params.transitions; written when the stride covers them) */
  float morph;                 /* geomorph factor of `level` toward the next coarser level, [0, 1] */
  int32_t previous_level;      /* the level fading out (-1: fading in from nothing); == level when no fade runs */
  float fade;                  /* weight of `level` in [0, 1]; previous_level's is 1 - fade; 1 when no fade runs */
} slod_selection;

typedef struct slod_frame_result {
  uint32_t size;               /* sizeof(slod_frame_result), set by slod_frame_result_init */
  uint64_t frame;              /* pass to slod_report_frame_time */
  float predicted_ms;          /* predicted cost of the chosen levels */
  uint32_t drawn_count, culled_count, dropped_count, switch_count;
  int over_budget;             /* nonzero when even the mandatory levels did not fit */
  uint32_t group_count;        /* view groups of the frame (1 for slod_select) */
} slod_frame_result;

static inline void slod_camera_init(slod_camera* camera) {
  if (!camera) return;
  memset(camera, 0, sizeof *camera);
  camera->size = (uint32_t)sizeof *camera;
  camera->eye[2] = 5.0f;
  camera->up[1] = 1.0f;
  camera->fov_y_deg = 60.0f;
  camera->viewport_width = 1280;
  camera->viewport_height = 720;
}
static inline void slod_frame_params_init(slod_frame_params* params) {
  if (!params) return;
  memset(params, 0, sizeof *params);
  params->size = (uint32_t)sizeof *params;
  params->budget_ms = 16.7f;
  params->pixels_per_cell = 1.0f;
  params->transitions = SLOD_TRANSITIONS_NONE;
  params->dt_ms = 1000.0f / 60.0f;
  params->fade_ms = 250.0f;
  params->morph_band = 0.3f;
  params->fade_budget_share = 0.1f;
  params->min_drop_px = 4.0f;
}
static inline void slod_frame_result_init(slod_frame_result* result) {
  if (!result) return;
  memset(result, 0, sizeof *result);
  result->size = (uint32_t)sizeof *result;
}
/* Selects one level per object. Writes slod_object_count() elements to out, out_stride bytes apart
 * (pass sizeof(slod_selection); at least 8, the object handle), of which capacity are available;
 * result (size set by slod_frame_result_init) may be null.
 * No heap allocation after the first frame (unless recording); one thread at a time per context. */
SLOD_API slod_status slod_select(slod_context* ctx, const slod_camera* camera, const slod_frame_params* params,
                                 void* out, size_t out_stride, size_t capacity, slod_frame_result* result);
/* ---- several views per frame: shadow cascades, stereo eyes, split screens (docs/SELECTION.md) ---- */

typedef enum slod_view_kind {
  SLOD_VIEW_PRIMARY = 0,
  SLOD_VIEW_SHADOW = 1,        /* an orthographic light camera, viewport in texels */
  SLOD_VIEW_EYE = 2,           /* both eyes of a stereo pair in one group */
  SLOD_VIEW_SECONDARY = 3      /* a mirror, a split screen */
} slod_view_kind;

typedef struct slod_view {
  uint32_t size;               /* sizeof(slod_view), set by slod_view_init */
  float eye[3], target[3], up[3]; /* defaults as slod_camera's */
  float fov_y_deg;             /* perspective field of view (default 60), when ortho_height is 0 */
  float ortho_height;          /* > 0: orthographic, the view's world-space height (default 0) */
  float near_plane, far_plane; /* default 0.05 and 1e6 */
  uint32_t viewport_width, viewport_height; /* pixels or texels, default 1280 x 720 */
  int kind;                    /* slod_view_kind, default SLOD_VIEW_PRIMARY */
  uint32_t group;              /* views with the same group get one level per object (default 0) */
  float pixels_per_cell;       /* X of this view (default 1); shadows may be coarser, e.g. 4 */
  float lod_bias;              /* multiplies X (default 1) */
} slod_view;

static inline void slod_view_init(slod_view* view) {
  if (!view) return;
  memset(view, 0, sizeof *view);
  view->size = (uint32_t)sizeof *view;
  view->eye[2] = 5.0f;
  view->up[1] = 1.0f;
  view->fov_y_deg = 60.0f;
  view->near_plane = 0.05f;
  view->far_plane = 1.0e6f;
  view->viewport_width = 1280;
  view->viewport_height = 720;
  view->pixels_per_cell = 1.0f;
  view->lod_bias = 1.0f;
}
/* Selects one level per object and view group for up to 8 views (stepped by views[0].size, the same
 * for all). Groups are numbered in order of first appearance; levels[group * object_count + object]
 * gets the level of the object written at index `object` of out (-1 where no view of the group sees
 * it), levels_capacity entries being available; out gets the primary group's levels as slod_select
 * writes them. A shadow group is never finer than the primary group where that sees the object.
 * params->budget_ms as for slod_select (params->pixels_per_cell is not read: each view has its own).
 * Needs slod_context_desc.max_view_groups >= the groups used; refused while recording. No heap
 * allocation after the first frame; one thread at a time per context. */
SLOD_API slod_status slod_select_views(slod_context* ctx, const slod_view* views, size_t view_count,
                                       const slod_frame_params* params, void* out, size_t out_stride, size_t capacity,
                                       int8_t* levels, size_t levels_capacity, slod_frame_result* result);
/* Reports how long frame `frame` really took, to calibrate the cost model. May be called from one
 * other thread while slod_select runs (lock-free hand-over). */
SLOD_API slod_status slod_report_frame_time(slod_context* ctx, uint64_t frame, float measured_ms);

typedef struct slod_pick_result {
  uint32_t size;               /* sizeof(slod_pick_result), set by slod_pick_result_init */
  slod_object object;          /* SLOD_NULL_OBJECT when nothing was hit */
  int32_t level;               /* the level drawn in the last selection, the one the ray hit */
  float point[3];              /* world-space hit point */
  float distance;
} slod_pick_result;

static inline void slod_pick_result_init(slod_pick_result* result) {
  if (!result) return;
  memset(result, 0, sizeof *result);
  result->size = (uint32_t)sizeof *result;
}
/* Casts a ray through pixel (x, y) (top-left origin) against the levels chosen by the last
 * slod_select; out's size is set by slod_pick_result_init. Not thread-safe on ctx. */
SLOD_API slod_status slod_pick(slod_context* ctx, const slod_camera* camera, float x, float y, slod_pick_result* out);

/* ---- record and replay ---- */

/* Starts recording: writes the scene (objects and chains) as a LOD pack at pack_path now, and from the
 * next slod_select on one replay line per frame (camera, moves, reported frame times); the replay file
 * (docs/REPLAY.md) is written by slod_record_stop. `scenelod replay` reproduces the selections exactly
 * when the same frame params are used throughout. */
SLOD_API slod_status slod_record_start(slod_context* ctx, const char* replay_path, const char* pack_path);
SLOD_API slod_status slod_record_stop(slod_context* ctx);

#ifdef __cplusplus
}
#endif

#endif /* SCENELOD_SCENELOD_H */
