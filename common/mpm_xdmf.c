/* The XDMF index series.xmf (see mpm_xdmf.h for the layout). Invariants:
 *
 * - entry[k].xml is one complete <Grid CollectionType="Spatial"> ... </Grid> element,
 *   starting at '<' and ending at '>', with no leading indentation; the writer places it.
 * - Entries are kept in the order added; indices are whatever the caller gave (the output
 *   layer numbers them 0, 1, 2, ... and continues after the largest kept one on a restart).
 * - Times are printed with %.17g, so a time read back compares equal to the one written
 *   and "time <= t_restart" on a restart keeps exactly the snapshots written up to then.
 *
 * Reading back is deliberately narrow: it finds the snapshot blocks of a file this module
 * wrote (by element nesting, not by line layout) and keeps their text verbatim. A block's
 * time is its first <Time> (the snapshot's; the grids inside repeat it). */
#define _POSIX_C_SOURCE 200809L /* strcasecmp */
#include "mpm_xdmf.h"
#include "mpm_safefile.h"
#include "mpm_error.h"
#include "mpm_types.h"

#include <errno.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

typedef struct xdmf_entry {
  double time;
  int index;
  char *xml;
} xdmf_entry;

struct mpm_xdmf {
  int dim;
  int n, cap;
  xdmf_entry *entry;
};

/* ---- a growing string ------------------------------------------------------------------ */

typedef struct strbuf {
  char *s;
  size_t len, cap;
  int failed; /* an allocation failed; later appends are ignored and the caller reports it */
} strbuf;

static void sb_reserve(strbuf *b, size_t extra) {
  if (b->failed || b->len + extra + 1 <= b->cap) return;
  size_t cap = b->cap ? b->cap : 1024;
  while (cap < b->len + extra + 1) cap *= 2;
  char *s = realloc(b->s, cap);
  if (!s) {
    b->failed = 1;
    return;
  }
  b->s = s, b->cap = cap;
}

static void sb_printf(strbuf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void sb_printf(strbuf *b, const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  const int k = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  if (k < 0) {
    b->failed = 1;
    return;
  }
  sb_reserve(b, (size_t)k);
  if (b->failed) return;
  va_start(ap, fmt);
  vsnprintf(b->s + b->len, b->cap - b->len, fmt, ap);
  va_end(ap);
  b->len += (size_t)k;
}

/* Names come from case files; escape them so that any name still gives well-formed XML. */
static void sb_escaped(strbuf *b, const char *s) {
  for (; *s; ++s) switch (*s) {
    case '&':
      sb_printf(b, "&amp;");
      break;
    case '<':
      sb_printf(b, "&lt;");
      break;
    case '>':
      sb_printf(b, "&gt;");
      break;
    case '"':
      sb_printf(b, "&quot;");
      break;
    case '\'':
      sb_printf(b, "&apos;");
      break;
    default:
      sb_printf(b, "%c", *s);
    }
}

/* ---- construction ---------------------------------------------------------------------- */

int mpm_xdmf_new(mpm_xdmf **x, int dim) {
  *x = NULL;
  if (dim != 2 && dim != 3) MPM_FAIL(MPM_ERR_INPUT, "XDMF index: dimension %d is not 2 or 3", dim);
  MPM_ALLOC(*x, 1);
  (*x)->dim = dim;
  return 0;
}

void mpm_xdmf_destroy(mpm_xdmf **x) {
  if (!x || !*x) return;
  for (int k = 0; k < (*x)->n; ++k) free((*x)->entry[k].xml);
  free((*x)->entry);
  free(*x);
  *x = NULL;
}

int mpm_xdmf_count(const mpm_xdmf *x) {
  return x->n;
}

int mpm_xdmf_next_index(const mpm_xdmf *x) {
  int next = 0;
  for (int k = 0; k < x->n; ++k) next = MPM_MAX(next, x->entry[k].index + 1);
  return next;
}

/* Take ownership of xml. */
static int push_entry(mpm_xdmf *x, double time, int index, char *xml) {
  if (x->n == x->cap) {
    const int cap = x->cap ? 2 * x->cap : 16;
    xdmf_entry *e = realloc(x->entry, (size_t)cap * sizeof *e);
    if (!e) {
      free(xml);
      MPM_FAIL(MPM_ERR_MEMORY, "XDMF index: cannot grow to %d entries", cap);
    }
    x->entry = e, x->cap = cap;
  }
  x->entry[x->n++] = (xdmf_entry){time, index, xml};
  return 0;
}

/* ---- rendering one snapshot ------------------------------------------------------------ */

/* The fields ParaView should colour by when a series is opened, in order of preference; a
 * phase lists the first it has as its only Scalar attribute (see mpm_xdmf.h). */
static const char *const g_colour_fields[] = {"rho"};

/* An HDF DataItem of precision bytes per number. */
static void data_item_p(strbuf *b, const char *indent, const char *dims, const char *type,
                        int precision, const char *file, const char *group, const char *name) {
  sb_printf(b, "%s<DataItem Dimensions=\"%s\" NumberType=\"%s\" Precision=\"%d\" Format=\"HDF\">",
            indent, dims, type, precision);
  sb_escaped(b, file);
  sb_printf(b, ":/");
  sb_escaped(b, group);
  sb_printf(b, "/");
  sb_escaped(b, name);
  sb_printf(b, "</DataItem>\n");
}

static void data_item(strbuf *b, const char *indent, const char *dims, const char *type,
                      const char *file, const char *group, const char *name) {
  data_item_p(b, indent, dims, type, 8, file, group, name);
}

/* The one-grid temporal collection that gives a block a stable place, and its grid's Time
 * (spelled with TimeType: one `<Time Value=` per entry). */
static void open_block(strbuf *b, const char *name, const char *suffix, double time) {
  sb_printf(b, "        <Grid Name=\"");
  sb_escaped(b, name);
  sb_printf(b, "%s\" GridType=\"Collection\" CollectionType=\"Temporal\">\n", suffix);
  sb_printf(b, "          <Grid Name=\"");
  sb_escaped(b, name);
  sb_printf(b, "%s\" GridType=\"Uniform\">\n", suffix);
  sb_printf(b, "            <Time TimeType=\"Single\" Value=\"%.17g\"/>\n", time);
}

static void close_block(strbuf *b) {
  sb_printf(b, "          </Grid>\n"
               "        </Grid>\n");
}

/* Index of the phase's colour field, or -1. */
static int colour_field(const mpm_xdmf_phase *ph) {
  for (size_t k = 0; k < sizeof g_colour_fields / sizeof g_colour_fields[0]; ++k)
    for (int f = 1; f < ph->nfields; ++f)
      if (ph->field[f].ncomp == 1 && strcmp(ph->field[f].name, g_colour_fields[k]) == 0) return f;
  return -1;
}

/* Scalar only for the colour field: the readers make the first Scalar the active scalars.
 * Vector for dim components (ParaView pads 2-D ones to 3), Tensor for 9, else a Matrix whose
 * components ParaView keeps in order. Tensor6 is avoided: its component order need not
 * match a 6-component field's. */
static const char *attribute_type(int ncomp, int dim, int colour) {
  if (colour) return "Scalar";
  if (ncomp == dim) return "Vector";
  if (ncomp == 9) return "Tensor";
  return "Matrix";
}

/* One-component fields are described as [n 1] (a Matrix needs its column count). */
static void render_field(strbuf *b, const char *file, const mpm_xdmf_phase *ph, int f, int dim,
                         int colour) {
  char dims[64];
  sb_printf(b, "            <Attribute Name=\"");
  sb_escaped(b, ph->field[f].name);
  sb_printf(b, "\" AttributeType=\"%s\" Center=\"Node\">\n",
            attribute_type(ph->field[f].ncomp, dim, colour));
  snprintf(dims, sizeof dims, "%" PRId64 " %d", ph->n, ph->field[f].ncomp);
  data_item(b, "              ", dims, "Float", file, ph->name, ph->field[f].name);
  sb_printf(b, "            </Attribute>\n");
}

/* XDMF has no component names, and ParaView numbers the components of a Matrix 0 .. n-1. So
 * each component of a tensor or history field is listed again as a one-column attribute of
 * its own name, a HyperSlab selecting that column of the field's dataset: nothing is stored
 * twice, and all three readers read it. Tensors (dim x dim components, row-major) give
 * NAME_xx NAME_xy ...; the fields below have names of their own. */
typedef struct named_components {
  const char *field;
  int ncomp;
  const char *name[8];
} named_components;

static const named_components g_named[] = {
    /* solid_j2.c's history: the symmetric Cp^-1 = Fp^-1 Fp^-T (3 x 3 also in plane strain),
     * then the equivalent plastic strain alpha */
    {"hist",
     7,
     {"Cp_inv_xx", "Cp_inv_yy", "Cp_inv_zz", "Cp_inv_xy", "Cp_inv_yz", "Cp_inv_xz", "eps_p_eq"}},
};

/* The name of component c of field f, in buf; 0 if its components are not named. */
static int component_name(const mpm_xdmf_field *f, int dim, int c, char *buf, size_t size) {
  for (size_t k = 0; k < sizeof g_named / sizeof g_named[0]; ++k)
    if (strcmp(f->name, g_named[k].field) == 0 && f->ncomp == g_named[k].ncomp)
      return snprintf(buf, size, "%s", g_named[k].name[c]), 1;
  if (f->ncomp != dim * dim) return 0;
  snprintf(buf, size, "%s_%c%c", f->name, "xyz"[c / dim], "xyz"[c % dim]);
  return 1;
}

/* Column c of field f as a one-column attribute (HyperSlab: start, stride, count). */
static void render_components(strbuf *b, const char *file, const mpm_xdmf_phase *ph, int f,
                              int dim) {
  const mpm_xdmf_field *fld = &ph->field[f];
  char name[96], dims[64];
  snprintf(dims, sizeof dims, "%" PRId64 " %d", ph->n, fld->ncomp);
  for (int c = 0; c < fld->ncomp && component_name(fld, dim, c, name, sizeof name); ++c) {
    sb_printf(b, "            <Attribute Name=\"");
    sb_escaped(b, name);
    sb_printf(b, "\" AttributeType=\"Matrix\" Center=\"Node\">\n");
    sb_printf(b,
              "              <DataItem ItemType=\"HyperSlab\" Dimensions=\"%" PRId64
              " 1\" Type=\"HyperSlab\">\n",
              ph->n);
    sb_printf(b,
              "                <DataItem Dimensions=\"3 2\" NumberType=\"Int\" "
              "Format=\"XML\">0 %d 1 1 %" PRId64 " 1</DataItem>\n",
              c, ph->n);
    data_item(b, "                ", dims, "Float", file, ph->name, fld->name);
    sb_printf(b, "              </DataItem>\n"
                 "            </Attribute>\n");
  }
}

/* Attributes in this order: the colour field, the other fields as stored (velocity first),
 * the named components, the id (a one-column Matrix: never the active scalars). */
static void render_phase(strbuf *b, const char *file, const mpm_xdmf_phase *ph, int dim,
                         double time) {
  char dims[64];
  open_block(b, ph->name, "", time);
  sb_printf(b,
            "            <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"%" PRId64
            "\" NodesPerElement=\"1\">\n",
            ph->n);
  snprintf(dims, sizeof dims, "%" PRId64, ph->n);
  data_item(b, "              ", dims, "Int", file, MPM_XDMF_VERTICES, ph->name);
  sb_printf(b, "            </Topology>\n");
  sb_printf(b, "            <Geometry GeometryType=\"%s\">\n", dim == 2 ? "XY" : "XYZ");
  snprintf(dims, sizeof dims, "%" PRId64 " %d", ph->n, dim);
  data_item(b, "              ", dims, "Float", file, ph->name, ph->field[0].name);
  sb_printf(b, "            </Geometry>\n");
  const int colour = colour_field(ph);
  if (colour > 0) render_field(b, file, ph, colour, dim, 1);
  for (int f = 1; f < ph->nfields; ++f)
    if (f != colour) render_field(b, file, ph, f, dim, 0);
  for (int f = 1; f < ph->nfields; ++f) render_components(b, file, ph, f, dim);
  sb_printf(b, "            <Attribute Name=\"id\" AttributeType=\"Matrix\" Center=\"Node\">\n");
  snprintf(dims, sizeof dims, "%" PRId64 " 1", ph->n);
  data_item(b, "              ", dims, "Int", file, ph->name, "id");
  sb_printf(b, "            </Attribute>\n");
  close_block(b);
}

/* A refinement level's masks as node attributes (mpm_xdmf.h). */
static void render_masks(strbuf *b, const char *file, const mpm_xdmf_mesh *m, const char *dims) {
  static const char *const mask[2] = {"active", "own"};
  char group[32];
  snprintf(group, sizeof group, MPM_XDMF_LEVELS "/%d", m->level);
  for (int k = 0; k < 2; ++k) {
    sb_printf(b, "            <Attribute Name=\"%s\" AttributeType=\"Scalar\" Center=\"Node\">\n",
              mask[k]);
    data_item_p(b, "              ", dims, "UChar", 1, file, group, mask[k]);
    sb_printf(b, "            </Attribute>\n");
  }
}

/* XDMF lists structured extents, origins and spacings slowest axis first (z y x). */
static void render_mesh(strbuf *b, const char *file, const mpm_xdmf_mesh *m, int dim, double time) {
  char dims[96], group[96], suffix[32] = "_grid";
  const double dz = m->spacing; /* also for the single layer of a 2-D lattice */
  snprintf(dims, sizeof dims, "%d %d %d", m->n[2], m->n[1], m->n[0]);
  if (m->level) snprintf(suffix, sizeof suffix, "_grid_l%d", m->level);
  open_block(b, m->name, suffix, time);
  sb_printf(b, "            <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"%s\"/>\n", dims);
  sb_printf(b, "            <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n");
  sb_printf(b,
            "              <DataItem Name=\"Origin\" Dimensions=\"3\" NumberType=\"Float\" "
            "Precision=\"8\" Format=\"XML\">%.17g %.17g %.17g</DataItem>\n",
            dim == 3 ? m->origin[2] : 0.0, m->origin[1], m->origin[0]);
  sb_printf(b,
            "              <DataItem Name=\"Spacing\" Dimensions=\"3\" NumberType=\"Float\" "
            "Precision=\"8\" Format=\"XML\">%.17g %.17g %.17g</DataItem>\n",
            dz, m->spacing, m->spacing);
  sb_printf(b, "            </Geometry>\n");
  if (m->level) /* names are checked to fit */
    snprintf(group, sizeof group, MPM_XDMF_LEVELS "/%d/%s", m->level, m->name);
  else
    snprintf(group, sizeof group, "grid/%s", m->name);
  sb_printf(b, "            <Attribute Name=\"m\" AttributeType=\"Scalar\" Center=\"Node\">\n");
  data_item(b, "              ", dims, "Float", file, group, "m");
  sb_printf(b, "            </Attribute>\n");
  sb_printf(b, "            <Attribute Name=\"v\" AttributeType=\"Vector\" Center=\"Node\">\n");
  snprintf(dims, sizeof dims, "%d %d %d %d", m->n[2], m->n[1], m->n[0], dim);
  data_item(b, "              ", dims, "Float", file, group, "v");
  sb_printf(b, "            </Attribute>\n");
  snprintf(dims, sizeof dims, "%d %d %d", m->n[2], m->n[1], m->n[0]);
  if (m->masks) render_masks(b, file, m, dims);
  close_block(b);
}

int mpm_xdmf_add(mpm_xdmf *x, double time, int index, const mpm_xdmf_phase *phase, int nphases,
                 const mpm_xdmf_mesh *mesh, int nmeshes) {
  char file[32];
  strbuf b = {0};
  snprintf(file, sizeof file, "snap_%06d.h5", index);
  for (int k = 0; k < nmeshes; ++k)
    if (strlen(mesh[k].name) > 64)
      MPM_FAIL(MPM_ERR_INPUT, "XDMF index: grid phase name '%s' is too long", mesh[k].name);
  sb_printf(&b,
            "<Grid Name=\"snap_%06d\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
            "        <Time Value=\"%.17g\"/>\n",
            index, time);
  for (int k = 0; k < nphases; ++k)
    if (phase[k].n > 0) render_phase(&b, file, &phase[k], x->dim, time);
  for (int k = 0; k < nmeshes; ++k) render_mesh(&b, file, &mesh[k], x->dim, time);
  sb_printf(&b, "      </Grid>");
  if (b.failed) {
    free(b.s);
    MPM_FAIL(MPM_ERR_MEMORY, "XDMF index: cannot render the entry of snapshot %d", index);
  }
  MPM_CALL(push_entry(x, time, index, b.s));
  return 0;
}

/* ---- writing --------------------------------------------------------------------------- */

static int write_all(const mpm_xdmf *x, FILE *f) {
  fprintf(f, "<?xml version=\"1.0\" ?>\n"
             "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
             "<Xdmf Version=\"2.0\">\n"
             "  <Domain>\n"
             "    <Grid Name=\"series\" GridType=\"Collection\" CollectionType=\"Temporal\">\n");
  for (int k = 0; k < x->n; ++k) fprintf(f, "      %s\n", x->entry[k].xml);
  fprintf(f, "    </Grid>\n"
             "  </Domain>\n"
             "</Xdmf>\n");
  return ferror(f) ? -1 : 0;
}

int mpm_xdmf_write(const mpm_xdmf *x, const char *path) {
  FILE *f = mpm_file_begin(path, "w");
  if (!f) return mpm_file_fail(path, errno, "XDMF index");
  if (write_all(x, f) != 0) {
    const int e = errno ? errno : EIO;
    mpm_file_abandon(f, path);
    return mpm_file_fail(path, e, "XDMF index");
  }
  const int e = mpm_file_commit(f, path);
  if (e) return mpm_file_fail(path, e, "XDMF index");
  return 0;
}

/* ---- reading back ---------------------------------------------------------------------- */

/* The end of the markup starting at p ('<'): one past its closing '>', skipping quoted
 * attribute values; NULL if the text ends first. */
static const char *markup_end(const char *p) {
  if (strncmp(p, "<!--", 4) == 0) {
    const char *e = strstr(p + 4, "-->");
    return e ? e + 3 : NULL;
  }
  char quote = 0;
  for (++p; *p; ++p) {
    if (quote) {
      if (*p == quote) quote = 0;
    } else if (*p == '"' || *p == '\'') {
      quote = *p;
    } else if (*p == '>') {
      return p + 1;
    }
  }
  return NULL;
}

/* Is the tag [p, end) an element named name ("<name" followed by a space, '/' or '>')? */
static int tag_is(const char *p, const char *end, const char *name) {
  const size_t n = strlen(name);
  return (size_t)(end - p) > n + 1 && strncmp(p + 1, name, n) == 0 &&
         strchr(" \t\r\n/>", p[1 + n]) != NULL;
}

/* Copy the value of attribute key of the tag [p, end) into val; 0 if found. */
static int tag_attr(const char *p, const char *end, const char *key, char *val, size_t size) {
  const size_t n = strlen(key);
  for (const char *q = p; q + n < end; ++q) {
    if (!strchr(" \t\r\n", *q) || strncmp(q + 1, key, n) != 0) continue;
    const char *r = q + 1 + n;
    while (r < end && strchr(" \t\r\n", *r)) ++r;
    if (r >= end || *r != '=') continue;
    ++r;
    while (r < end && strchr(" \t\r\n", *r)) ++r;
    if (r >= end || (*r != '"' && *r != '\'')) continue;
    const char quote = *r++;
    const char *e = memchr(r, quote, (size_t)(end - r));
    if (!e || (size_t)(e - r) >= size) return -1;
    memcpy(val, r, (size_t)(e - r));
    val[e - r] = 0;
    return 0;
  }
  return -1;
}

/* The snapshot block being read: its start, time and index once seen. */
typedef struct block_state {
  const char *start;
  int depth; /* Grid nesting depth at which the block opened */
  int has_time, index;
  double time;
} block_state;

static int block_open(block_state *s, const char *p, const char *end, int depth) {
  char val[64];
  s->start = p, s->depth = depth, s->has_time = 0, s->index = -1;
  if (tag_attr(p, end, "Name", val, sizeof val) == 0) sscanf(val, "snap_%d", &s->index);
  return 0;
}

static int block_close(mpm_xdmf *x, block_state *s, const char *end, const char *path,
                       double t_max) {
  if (!s->has_time || s->index < 0)
    MPM_FAIL(MPM_ERR_INPUT,
             "%s: a snapshot entry lacks its <Time> or its snap_NNNNNN name; this is not an "
             "index mpmfsi wrote. Move the file away (or restart into a new output directory)",
             path);
  if (s->time <= t_max) {
    const size_t len = (size_t)(end - s->start);
    char *xml;
    MPM_ALLOC(xml, len + 1);
    memcpy(xml, s->start, len);
    xml[len] = 0;
    MPM_CALL(push_entry(x, s->time, s->index, xml));
  }
  s->start = NULL;
  return 0;
}

static int parse_index(mpm_xdmf *x, const char *text, const char *path, double t_max) {
  block_state s = {0};
  int depth = 0, seen_xdmf = 0;
  for (const char *p = strchr(text, '<'); p; p = strchr(p, '<')) {
    const char *end = markup_end(p);
    if (!end) break;
    const int closing = p[1] == '/', empty = end[-2] == '/';
    if (tag_is(p, end, "Xdmf")) seen_xdmf = 1;
    if (closing && strncmp(p, "</Grid", 6) == 0) {
      --depth;
      if (s.start && depth == s.depth) MPM_CALL(block_close(x, &s, end, path, t_max));
    } else if (!closing && tag_is(p, end, "Grid")) {
      char type[32];
      if (!empty && !s.start && tag_attr(p, end, "CollectionType", type, sizeof type) == 0 &&
          strcasecmp(type, "Spatial") == 0)
        block_open(&s, p, end, depth);
      if (!empty) ++depth;
    } else if (s.start && !s.has_time && tag_is(p, end, "Time")) { /* the snapshot's */
      char val[64];
      char *e;
      if (tag_attr(p, end, "Value", val, sizeof val) == 0) {
        s.time = strtod(val, &e);
        s.has_time = e != val;
      }
    }
    p = end;
  }
  if (!seen_xdmf || depth != 0 || s.start)
    MPM_FAIL(MPM_ERR_INPUT,
             "%s is not a complete XDMF index (truncated, or not written by mpmfsi). Move it "
             "away to restart without the earlier snapshots in the index",
             path);
  return 0;
}

static int read_text(const char *path, char **text, int *found) {
  *text = NULL;
  FILE *f = fopen(path, "rb");
  if (!f) {
    if (errno == ENOENT) return *found = 0, 0;
    MPM_FAIL(MPM_ERR_FILE, "cannot read the XDMF index %s: %s", path, strerror(errno));
  }
  *found = 1;
  size_t len = 0, cap = 1 << 16;
  char *s = malloc(cap);
  while (s) {
    len += fread(s + len, 1, cap - len - 1, f);
    if (len < cap - 1) break;
    char *t = realloc(s, cap *= 2);
    if (!t) free(s);
    s = t;
  }
  const int bad = ferror(f);
  fclose(f);
  if (!s) MPM_FAIL(MPM_ERR_MEMORY, "cannot hold the XDMF index %s in memory", path);
  s[len] = 0;
  if (bad) {
    free(s);
    MPM_FAIL(MPM_ERR_FILE, "error while reading the XDMF index %s", path);
  }
  *text = s;
  return 0;
}

int mpm_xdmf_load(mpm_xdmf *x, const char *path, double t_max, int *found) {
  char *text;
  MPM_CALL(read_text(path, &text, found));
  if (!*found) return 0;
  const int rc = parse_index(x, text, path, t_max);
  free(text);
  MPM_CALL(rc);
  return 0;
}
