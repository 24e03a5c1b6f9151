/* A small time-critical simulator frame loop in C driving scenelod through its C API.
 *
 * Thousands of objects (a few shared meshes) move every frame; the loop runs at a fixed target frame
 * time, asks scenelod for one level per object under a render budget, "renders" with a synthetic
 * renderer (a busy wait proportional to what is drawn, as a GPU-bound frame would take), reports the
 * measured render time back so the cost model calibrates, and prints frame time against budget.
 * With --record DIR it records a replay (DIR/frame_loop.jsonl with the scene as DIR/frame_loop.pack)
 * that `scenelod replay` reproduces exactly, and --log FILE writes the levels chosen per frame.
 *
 *   frame_loop [--objects N] [--frames N] [--budget MS] [--hz HZ] [--record DIR] [--log FILE] */
#define _POSIX_C_SOURCE 199309L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "scenelod/scenelod.h"

static double nowMs(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

static void sleepMs(double ms) {
  struct timespec ts;
  if (ms <= 0.0) return;
  ts.tv_sec = (time_t)(ms / 1e3);
  ts.tv_nsec = (long)((ms - (double)ts.tv_sec * 1e3) * 1e6);
  nanosleep(&ts, NULL);
}

/* a closed mesh: a torus with `rings` x `sides` quads, radii R and r */
static slod_status buildTorusChain(slod_context* ctx, int rings, int sides, float R, float r, slod_chain* chain) {
  const size_t vc = (size_t)rings * (size_t)sides, ic = vc * 6;
  float* p = (float*)malloc(vc * 3 * sizeof(float));
  uint32_t* idx = (uint32_t*)malloc(ic * sizeof(uint32_t));
  slod_mesh_desc md;
  slod_chain_desc cd;
  slod_status st;
  size_t k = 0;
  int i, j;
  if (!p || !idx) {
    free(p);
    free(idx);
    return SLOD_ERROR_OUT_OF_MEMORY;
  }
  for (i = 0; i < rings; ++i)
    for (j = 0; j < sides; ++j) {
      const double u = 2.0 * 3.14159265358979 * i / rings, v = 2.0 * 3.14159265358979 * j / sides;
      float* q = p + 3 * ((size_t)i * (size_t)sides + (size_t)j);
      q[0] = (float)((R + r * cos(v)) * cos(u));
      q[1] = (float)(r * sin(v));
      q[2] = (float)((R + r * cos(v)) * sin(u));
    }
  for (i = 0; i < rings; ++i)
    for (j = 0; j < sides; ++j) {
      const uint32_t a = (uint32_t)(i * sides + j), b = (uint32_t)(((i + 1) % rings) * sides + j);
      const uint32_t c = (uint32_t)(i * sides + (j + 1) % sides), d = (uint32_t)(((i + 1) % rings) * sides + (j + 1) % sides);
      idx[k++] = a; idx[k++] = c; idx[k++] = b;
      idx[k++] = c; idx[k++] = d; idx[k++] = b;
    }
  slod_mesh_desc_init(&md);
  md.positions = p;
  md.vertex_count = vc;
  md.indices = idx;
  md.index_count = ic;
  md.name = "torus";
  slod_chain_desc_init(&cd);
  cd.level_count = 6;
  st = slod_chain_build(ctx, &md, &cd, chain);
  free(p);
  free(idx);
  return st;
}

int main(int argc, char** argv) {
  int objects = 3000, frames = 240, i, f;
  double budget_ms = 6.0, hz = 60.0;
  const char* record_dir = NULL;
  const char* log_path = NULL;
  slod_context_desc cd;
  slod_context* ctx = NULL;
  slod_object* handles;
  slod_selection* sel;
  slod_chain chains[3];
  uint32_t* tri_count[3];
  slod_camera cam;
  slod_frame_params fp;
  FILE* log = NULL;
  double frame_ms_sum = 0.0, worst_ms = 0.0;
  int within = 0, counted = 0;
  unsigned rng = 12345u;

  for (i = 1; i < argc; ++i) {
    if (!strcmp(argv[i], "--objects") && i + 1 < argc) objects = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--frames") && i + 1 < argc) frames = atoi(argv[++i]);
    else if (!strcmp(argv[i], "--budget") && i + 1 < argc) budget_ms = atof(argv[++i]);
    else if (!strcmp(argv[i], "--hz") && i + 1 < argc) hz = atof(argv[++i]);
    else if (!strcmp(argv[i], "--record") && i + 1 < argc) record_dir = argv[++i];
    else if (!strcmp(argv[i], "--log") && i + 1 < argc) log_path = argv[++i];
    else {
      fprintf(stderr, "usage: frame_loop [--objects N] [--frames N] [--budget MS] [--hz HZ] [--record DIR] [--log FILE]\n");
      return 2;
    }
  }
  if (objects <= 0 || frames <= 0 || budget_ms <= 0.0 || hz <= 0.0) {
    fprintf(stderr, "frame_loop: --objects, --frames, --budget and --hz must be positive\n");
    return 2;
  }

  slod_context_desc_init(&cd);
  cd.max_objects = (size_t)objects;
  if (slod_context_create(&cd, &ctx) != SLOD_OK) {
    fprintf(stderr, "frame_loop: cannot create the context\n");
    return 1;
  }
  /* three shared meshes of different density */
  for (i = 0; i < 3; ++i) {
    uint32_t l, n;
    if (buildTorusChain(ctx, 48 + 48 * i, 24 + 8 * i, 1.0f, 0.25f + 0.1f * (float)i, &chains[i]) != SLOD_OK) {
      fprintf(stderr, "frame_loop: %s\n", slod_last_error_message(ctx));
      return 1;
    }
    n = slod_chain_level_count(ctx, chains[i]);
    tri_count[i] = (uint32_t*)malloc(n * sizeof(uint32_t));
    for (l = 0; l < n; ++l) {
      slod_level_data ld;
      slod_level_data_init(&ld);
      slod_level_get(ctx, chains[i], l, &ld);
      tri_count[i][l] = ld.triangle_count + ld.edge_count + ld.point_count;
    }
  }
  handles = (slod_object*)malloc((size_t)objects * sizeof(slod_object));
  sel = (slod_selection*)malloc((size_t)objects * sizeof(slod_selection));
  for (i = 0; i < objects; ++i) {
    slod_object_desc od;
    slod_object_desc_init(&od);
    od.chain = chains[i % 3];
    rng = rng * 1664525u + 1013904223u;
    od.translation[0] = (float)((int)(rng >> 8) % 200 - 100);
    rng = rng * 1664525u + 1013904223u;
    od.translation[2] = (float)((int)(rng >> 8) % 200 - 100);
    od.user_data = (uint64_t)i;
    od.must_draw = (i == 0); /* the simulator's instrument panel */
    if (slod_object_add(ctx, &od, &handles[i]) != SLOD_OK) {
      fprintf(stderr, "frame_loop: %s\n", slod_last_error_message(ctx));
      return 1;
    }
  }
  if (record_dir) {
    char rp[1024], pp[1024];
    snprintf(rp, sizeof rp, "%s/frame_loop.jsonl", record_dir);
    snprintf(pp, sizeof pp, "%s/frame_loop.pack", record_dir);
    if (slod_record_start(ctx, rp, pp) != SLOD_OK) {
      fprintf(stderr, "frame_loop: %s\n", slod_last_error_message(ctx));
      return 1;
    }
  }
  if (log_path && !(log = fopen(log_path, "w"))) {
    fprintf(stderr, "frame_loop: cannot write %s\n", log_path);
    return 1;
  }

  slod_camera_init(&cam);
  slod_frame_params_init(&fp);
  fp.budget_ms = (float)budget_ms;
  for (f = 0; f < frames; ++f) {
    const double start = nowMs(), t = f / hz;
    slod_frame_result fr;
    double render_ms, work = 0.0, frame_ms;
    /* the camera circles the field; a tenth of the objects bob up and down */
    cam.eye[0] = (float)(120.0 * cos(0.2 * t));
    cam.eye[1] = 25.0f;
    cam.eye[2] = (float)(120.0 * sin(0.2 * t));
    for (i = 0; i < objects; i += 10) {
      const float tr[3] = {(float)((i * 37) % 200 - 100), (float)(2.0 * sin(t + i)), (float)((i * 91) % 200 - 100)};
      const float q[4] = {0.0f, (float)sin(0.5 * t), 0.0f, (float)cos(0.5 * t)};
      slod_object_set_trs(ctx, handles[i], tr, q, 1.0f);
    }
    slod_frame_result_init(&fr);
    if (slod_select(ctx, &cam, &fp, sel, sizeof(slod_selection), (size_t)objects, &fr) != SLOD_OK) {
      fprintf(stderr, "frame_loop: %s\n", slod_last_error_message(ctx));
      return 1;
    }
    /* synthetic renderer: 4 ns per primitive and 1 us per drawn object, spent in a busy wait */
    for (i = 0; i < objects; ++i)
      if (sel[i].level >= 0) work += 1e-3 + 4e-6 * tri_count[sel[i].user_data % 3][sel[i].level];
    {
      const double rs = nowMs();
      while (nowMs() - rs < work) {
      }
      render_ms = nowMs() - rs;
    }
    slod_report_frame_time(ctx, fr.frame, (float)render_ms);
    if (log) {
      fprintf(log, "{\"frame\": %d, \"levels\": [", f);
      for (i = 0; i < objects; ++i) fprintf(log, "%s%d", i ? "," : "", sel[i].level);
      fprintf(log, "]}\n");
    }
    frame_ms = nowMs() - start;
    frame_ms_sum += frame_ms;
    if (f >= 30) {
      ++counted;
      if (render_ms <= budget_ms * 1.1) ++within;
      if (render_ms > worst_ms) worst_ms = render_ms;
    }
    sleepMs(1000.0 / hz - frame_ms); /* hold the fixed frame rate */
  }
  if (record_dir && slod_record_stop(ctx) != SLOD_OK) {
    fprintf(stderr, "frame_loop: %s\n", slod_last_error_message(ctx));
    return 1;
  }
  if (log) fclose(log);
  printf("frame_loop: %d objects, %d frames at %.0f Hz, render budget %.2f ms\n", objects, frames, hz, budget_ms);
  printf("frame_loop: mean frame work %.2f ms; after 30 warm-up frames %d of %d renders within +10%% of the budget, "
         "worst %.2f ms\n",
         frame_ms_sum / frames, within, counted, worst_ms);
  for (i = 0; i < 3; ++i) free(tri_count[i]);
  free(handles);
  free(sel);
  slod_context_destroy(ctx);
  return 0;
}
