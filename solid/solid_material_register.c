/* The registry of built-in material models. Add a model here with one line. */
#include "solid_material.h"

#include "mpm_error.h"

#include <stdlib.h>
#include <stdio.h>
#include <string.h>

extern const solid_material_ops solid_linear_elastic_ops;
extern const solid_material_ops solid_stvk_ops;
extern const solid_material_ops solid_neo_hookean_ops;
extern const solid_material_ops solid_hypoelastic_ops;
extern const solid_material_ops solid_j2_ops;
extern const solid_material_ops solid_rigid_ops;

static const solid_material_ops *const g_models[] = {
    &solid_linear_elastic_ops, &solid_stvk_ops, &solid_neo_hookean_ops,
    &solid_hypoelastic_ops,    &solid_j2_ops,   &solid_rigid_ops,
};
static const int g_nmodels = (int)(sizeof g_models / sizeof g_models[0]);

const char *solid_material_names(void) {
  static char names[256];
  if (!names[0])
    for (int k = 0; k < g_nmodels; ++k)
      snprintf(names + strlen(names), sizeof names - strlen(names), "%s%s", k ? "|" : "",
               g_models[k]->name);
  return names;
}

int solid_material_count(void) {
  return g_nmodels;
}
const solid_material_ops *solid_material_ops_at(int k) {
  return g_models[k];
}

int solid_material_create(solid_material **mat, const char *type, const mpm_config *cfg,
                          const char *section, int dim) {
  for (int k = 0; k < g_nmodels; ++k) {
    if (strcmp(g_models[k]->name, type) != 0) continue;
    MPM_ALLOC(*mat, 1);
    (*mat)->ops = g_models[k];
    (*mat)->dim = dim;
    int rc = g_models[k]->create(*mat, cfg, section, dim);
    if (rc) {
      solid_material_destroy(mat);
      return mpm_trace(__FILE__, __LINE__, __func__, rc);
    }
    return 0;
  }
  char key[128];
  snprintf(key, sizeof key, "%s.material", section);
  return mpm_config_fail(cfg, key, "unknown material model '%s'; registered models: %s", type,
                         solid_material_names());
}

void solid_material_destroy(solid_material **mat) {
  if (!mat || !*mat) return;
  if ((*mat)->ops && (*mat)->ops->destroy) (*mat)->ops->destroy(*mat);
  free(*mat);
  *mat = NULL;
}
