/* Names of the shape functions, for case files and output. */
#include "mpm_shape.h"

#include <string.h>

static const char *const g_names[MPM_SHAPE_COUNT] = {"linear", "gimp", "quadratic", "cubic"};

int mpm_shape_parse(const char *name) {
  for (int k = 0; k < MPM_SHAPE_COUNT; ++k)
    if (strcmp(name, g_names[k]) == 0) return k;
  return -1;
}

const char *mpm_shape_name(mpm_shape_kind kind) {
  return (unsigned)kind < MPM_SHAPE_COUNT ? g_names[kind] : "unknown";
}
