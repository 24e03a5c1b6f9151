/* What the C API tests share: CHECK, which reports a failed condition and counts it, finish, which
 * turns the count into the exit status, and a UV sphere to build chains from. */
#ifndef SCENELOD_TESTS_CAPI_TEST_SUPPORT_H
#define SCENELOD_TESTS_CAPI_TEST_SUPPORT_H

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

static int failures = 0;
#define CHECK(cond)                                                             \
  do {                                                                          \
    if (!(cond)) {                                                              \
      fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
      ++failures;                                                               \
    }                                                                           \
  } while (0)

/* The exit status of a test program named `name`: 0 when every check passed. */
static int finish(const char* name) {
  if (failures) {
    fprintf(stderr, "%s: %d checks failed\n", name, failures);
    return 1;
  }
  printf("%s: all checks passed\n", name);
  return 0;
}

/* A UV sphere of radius 1 with rings x segments quads (the caller frees both arrays). */
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

#endif
