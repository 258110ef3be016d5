/* Particle storage for one module: structure of arrays, component-major.
 *
 * A particle set has named fields (x, v, F, m, ...), each with ncomp components. All reals
 * live in one block `data` of ncomp_total * n doubles: component c of every particle is the
 * contiguous run data[c*n .. c*n + n). The first `nstate` components (the state fields,
 * listed first) form the module's ODE state, which ARKODE integrates as one serial
 * N_Vector wrapping data[0 .. nstate*n). By convention field 0 is the position x and field 1
 * the velocity v, each with dim components.
 *
 * Ids are global and survive migration, sorting, injection and removal. Every change of the
 * particle count goes through mpm_particles_edit(), which rebuilds the block; callers that
 * hold an N_Vector over the state must re-wrap it (and call the integrator's Resize). */
#ifndef MPM_PARTICLES_H
#define MPM_PARTICLES_H

#include "mpm_grid.h"
#include "mpm_types.h"

#include <limits.h>
#include <stddef.h>

/* Fields of a set at most. The gas under an ERK pair with viscosity and the riemann limiter
 * needs 18 (tests/unit/test_layouts.c builds every module's layouts); the derived and scratch
 * masks below hold one bit per field. */
#define MPM_PARTICLES_MAX_FIELDS 32
/* Components of one field at most: a dim x dim tensor. A quantity with more is several fields
 * (the gas's pending strain rate is pending_divv, pending_D, pending_psi); the checkpoint
 * reader takes a larger stored size for damage. */
#define MPM_PARTICLES_MAX_NCOMP (MPM_MAX_DIM * MPM_MAX_DIM)
/* Components of all fields at most. */
#define MPM_PARTICLES_MAX_COMPONENTS (MPM_PARTICLES_MAX_FIELDS * MPM_PARTICLES_MAX_NCOMP)

typedef struct mpm_field_desc {
  const char *name;
  int ncomp;
} mpm_field_desc;

/* What a valid value of a field is, for data read from outside the run (a checkpoint):
 * always finite, and with MPM_FIELD_BOUNDED (which mpm_particles_set_range adds) within
 * [lo, hi], lo itself excluded with MPM_FIELD_LO_OPEN, and an integer with
 * MPM_FIELD_INTEGER (an index or flag stored as a double). A zeroed range: any finite value. */
enum { MPM_FIELD_INTEGER = 1, MPM_FIELD_LO_OPEN = 2, MPM_FIELD_BOUNDED = 4 };
typedef struct mpm_field_range {
  double lo, hi;
  int flags;
} mpm_field_range;

typedef struct mpm_particles {
  int dim;
  int nfields, nstate_fields;
  mpm_field_desc field[MPM_PARTICLES_MAX_FIELDS];
  int offset[MPM_PARTICLES_MAX_FIELDS]; /* first component of each field */
  int ncomp;                            /* components in all fields */
  int nstate;                           /* components in the state fields */
  mpm_lidx n;                           /* particles on this rank */
  mpm_gidx *id;
  double *data;
  /* Room of the block (id, data) in particles, and the block an edit replaced, kept for the
   * next edit: particles change at nearly every step (inflow, outflow, migration), and a fresh
   * block each time costs page faults and zeroing. */
  mpm_lidx cap, spare_cap;
  mpm_gidx *spare_id;
  double *spare_data;
  mpm_gidx id_next;                                /* next free global id; equal on every rank */
  mpm_field_range range[MPM_PARTICLES_MAX_FIELDS]; /* all reals unless the module narrows it */
  unsigned derived; /* bit f: field f is derived (mpm_particles_set_derived) */
  unsigned scratch; /* bit f: field f is scratch (mpm_particles_set_scratch) */
  /* An edit recorded by mpm_particles_edit_deferred for the next migration (owned buffers;
   * set while one is pending). */
  struct {
    int set;
    unsigned char *keep; /* p->n flags, or NULL: keep all */
    mpm_lidx nadd;
    mpm_gidx *id;
    double *data; /* component-major, stride nadd */
  } later;
} mpm_particles;

_Static_assert(MPM_PARTICLES_MAX_FIELDS <= sizeof(unsigned) * CHAR_BIT,
               "the derived and scratch masks need a bit per field");

/* A set with no particles. The first nstate_fields fields are the state; fields 0 and 1
 * must be x and v with dim components each. */
int mpm_particles_new(mpm_particles **p, int dim, const mpm_field_desc *fields, int nfields,
                      int nstate_fields);
void mpm_particles_destroy(mpm_particles **p);

/* Start of component c of field f. */
static inline double *mpm_particles_comp(const mpm_particles *p, int f, int c) {
  return p->data + (size_t)(p->offset[f] + c) * (size_t)p->n;
}

/* Field index by name, or -1. */
int mpm_particles_find(const mpm_particles *p, const char *name);

/* Keep the particles with keep[i] != 0 (all if keep is NULL), in order, and append nadd new
 * ones with ids add_id and data add_data (component-major: ncomp * nadd). With add_data NULL
 * the new particles' data is left undefined for the caller to fill in the new block (no copy
 * of the new particles is held beside the set: the gas's split, fluid_split.c). Local. */
int mpm_particles_edit(mpm_particles *p, const unsigned char *keep, mpm_lidx nadd,
                       const mpm_gidx *add_id, const double *add_data);

/* mpm_particles_edit, recorded now and applied by the next mpm_particles_migrate in the same
 * rebuild of the block as the migration itself: a set that changes at a boundary and then
 * migrates at every step is rebuilt once instead of twice, with the particles in the order the
 * edit and the migration one after the other give. Takes ownership of keep (p->n flags, or
 * NULL), add_id and add_data (nadd particles, component-major with stride nadd), all from
 * malloc. Nothing may read or change the set until the migration: the other editing calls
 * fail while an edit is pending. Local. */
int mpm_particles_edit_deferred(mpm_particles *p, unsigned char *keep, mpm_lidx nadd,
                                mpm_gidx *add_id, double *add_data);

/* Append nadd particles with fresh global ids (collective: ids are numbered in rank
 * order from id_next). */
int mpm_particles_inject(mpm_particles *p, MPI_Comm comm, mpm_lidx nadd, const double *add_data);

/* Send every particle to the rank owning its cell, after wrapping positions that left
 * through a periodic face back into the domain. *changed (may be NULL) is set to 1 on every
 * rank if any rank's set changed, a wrapped position included. A particle outside the
 * domain (beyond a non-periodic face, or more than a period away) is an error naming
 * its id and position. Collective over grid->comm. */
int mpm_particles_migrate(mpm_particles *p, const mpm_grid *grid, int *changed);

/* Reorder the particles by the cell that contains them (x fastest), stably. Local. */
int mpm_particles_sort(mpm_particles *p, const mpm_grid *grid);

/* Narrow the valid values of field f (see mpm_field_range); the module that owns the set
 * says what its fields mean. */
void mpm_particles_set_range(mpm_particles *p, int f, double lo, double hi, int flags);

/* Mark field f as derived: the module recomputes it from the other fields before every use
 * (an output field, filled just before a snapshot), so its values need not survive an edit, a
 * sort or a migration, and those leave them undefined instead of moving them. */
void mpm_particles_set_derived(mpm_particles *p, int f);

/* Mark field f as scratch: every step writes it before it reads it (the ERK pairs' pending
 * strain rate), so a checkpoint need not hold it: a restart from one written without it (under
 * another time.method) starts it at zero. */
void mpm_particles_set_scratch(mpm_particles *p, int f);

/* Check n particles given as ids and component-major data (stride n) in p's layout: every
 * id >= 0 (ids beyond id_next are legal: the gas's inflow hands out its own ranges) and
 * every value valid for its field. Returns the index of the first
 * invalid particle and describes it in why, or -1 if all are valid. Local. */
mpm_lidx mpm_particles_find_invalid(const mpm_particles *p, mpm_lidx n, const mpm_gidx *id,
                                    const double *data, char *why, size_t size);

/* Are the n ids on each rank unique over all ranks? Sets *dup to the
 * smallest id held twice, or -1, the same on every rank. O(N log N) over the ranks: each id
 * is checked by the rank id % size. Collective. */
int mpm_particles_find_duplicate(MPI_Comm comm, const mpm_gidx *id, mpm_lidx n, mpm_gidx *dup);

/* Global particle count (collective). */
int mpm_particles_global_count(const mpm_particles *p, MPI_Comm comm, mpm_gidx *count);

#endif
