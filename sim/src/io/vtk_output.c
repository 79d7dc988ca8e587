/* VTK XML output: PolyData (.vtp) snapshots with raw appended binary data, and .pvd time
 * collections. See surge/vtk_output.h. */
#define _POSIX_C_SOURCE 200809L

#include "surge/platform.h"
#include "surge/vtk_output.h"

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* Particles staged per fwrite when arrays have to be interleaved or converted. */
#define CHUNK_PARTICLES 1024

/* ------------------------------------------------------------------------------------------------
 * Small helpers
 * --------------------------------------------------------------------------------------------- */

static void set_err(char *err, size_t err_len, const char *fmt, ...)
{
    if (err == NULL || err_len == 0) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, err_len, fmt, ap);
    va_end(ap);
}

static char *dup_string(const char *s)
{
    size_t len = strlen(s) + 1;
    char *copy = malloc(len);
    if (copy != NULL) {
        memcpy(copy, s, len);
    }
    return copy;
}

static int host_is_little_endian(void)
{
    const uint16_t one = 1;
    unsigned char first;
    memcpy(&first, &one, 1);
    return first == 1;
}

/* ------------------------------------------------------------------------------------------------
 * Atomic output file: written to "<path>.tmp", renamed over <path> on commit.
 * Write errors are sticky: after the first failure all writes are skipped and commit reports it.
 * --------------------------------------------------------------------------------------------- */

typedef struct out_file {
    const char *path;
    char *tmp_path;
    FILE *file;
    int error;        /* errno of the first failed write; 0 while all is well */
    int little_endian;
} out_file;

static int out_open(out_file *o, const char *path, char *err, size_t err_len)
{
    o->path = path;
    o->file = NULL;
    o->error = 0;
    o->little_endian = host_is_little_endian();
    size_t len = strlen(path);
    o->tmp_path = malloc(len + sizeof ".tmp");
    if (o->tmp_path == NULL) {
        set_err(err, err_len, "cannot write '%s': out of memory", path);
        return -1;
    }
    memcpy(o->tmp_path, path, len);
    memcpy(o->tmp_path + len, ".tmp", sizeof ".tmp");
    o->file = surge_fopen_waiting(o->tmp_path, "wb");
    if (o->file == NULL) {
        set_err(err, err_len, "cannot open '%s' for writing: %s", o->tmp_path, strerror(errno));
        free(o->tmp_path);
        o->tmp_path = NULL;
        return -1;
    }
    return 0;
}

/* Closes the temporary file and renames it over the target; on any failure (including earlier
 * write errors) removes the temporary file instead. Always releases o's resources. */
static int out_commit(out_file *o, char *err, size_t err_len)
{
    int rc = 0;
    if (o->error != 0) {
        set_err(err, err_len, "error writing '%s': %s", o->tmp_path, strerror(o->error));
        fclose(o->file);
        rc = -1;
    } else if (fclose(o->file) != 0) {
        set_err(err, err_len, "error closing '%s': %s", o->tmp_path, strerror(errno));
        rc = -1;
    } else if (rename(o->tmp_path, o->path) != 0) {
        set_err(err, err_len, "cannot rename '%s' to '%s': %s", o->tmp_path, o->path, strerror(errno));
        rc = -1;
    }
    if (rc != 0) {
        remove(o->tmp_path);
    }
    free(o->tmp_path);
    o->tmp_path = NULL;
    o->file = NULL;
    return rc;
}

static void put_bytes(out_file *o, const void *data, size_t size)
{
    if (o->error != 0 || size == 0) {
        return;
    }
    errno = 0;
    if (fwrite(data, 1, size, o->file) != size) {
        o->error = errno != 0 ? errno : EIO;
    }
}

static void put_text(out_file *o, const char *fmt, ...)
{
    if (o->error != 0) {
        return;
    }
    va_list ap;
    va_start(ap, fmt);
    errno = 0;
    if (vfprintf(o->file, fmt, ap) < 0) {
        o->error = errno != 0 ? errno : EIO;
    }
    va_end(ap);
}

/* Writes count elements of elem_size bytes each, in little-endian byte order whatever the host. */
static void put_le(out_file *o, const void *data, size_t elem_size, size_t count)
{
    if (o->little_endian || elem_size == 1) {
        put_bytes(o, data, elem_size * count);
        return;
    }
    unsigned char swapped[4096];
    const unsigned char *src = data;
    size_t per_pass = sizeof swapped / elem_size;
    while (count > 0) {
        size_t k = count < per_pass ? count : per_pass;
        for (size_t i = 0; i < k; i++) {
            for (size_t b = 0; b < elem_size; b++) {
                swapped[i * elem_size + b] = src[i * elem_size + elem_size - 1 - b];
            }
        }
        put_bytes(o, swapped, k * elem_size);
        src += k * elem_size;
        count -= k;
    }
}

/* ------------------------------------------------------------------------------------------------
 * .vtp writer
 * --------------------------------------------------------------------------------------------- */

/* Prints one appended DataArray tag at the running offset and advances it past the block
 * (UInt64 byte count + data). ncomp == 0 writes a field-data tag (NumberOfTuples="1"). */
static void array_tag(out_file *o, const char *indent, const char *type, const char *name, int ncomp,
                      uint64_t nbytes, uint64_t *offset)
{
    put_text(o, "%s<DataArray type=\"%s\" Name=\"%s\" ", indent, type, name);
    if (ncomp == 0) {
        put_text(o, "NumberOfTuples=\"1\" ");
    } else if (ncomp > 1) {
        put_text(o, "NumberOfComponents=\"%d\" ", ncomp);
    }
    put_text(o, "format=\"appended\" offset=\"%" PRIu64 "\"/>\n", *offset);
    *offset += sizeof(uint64_t) + nbytes;
}

static void block_header(out_file *o, uint64_t nbytes)
{
    put_le(o, &nbytes, sizeof nbytes, 1);
}

/* Writes (a[i], b[i], 0) triples as Float64. */
static void put_xyz_f64(out_file *o, const double *a, const double *b, size_t n)
{
    double buf[3 * CHUNK_PARTICLES];
    for (size_t start = 0; start < n; start += CHUNK_PARTICLES) {
        size_t k = n - start < CHUNK_PARTICLES ? n - start : CHUNK_PARTICLES;
        for (size_t i = 0; i < k; i++) {
            buf[3 * i] = a[start + i];
            buf[3 * i + 1] = b[start + i];
            buf[3 * i + 2] = 0.0;
        }
        put_le(o, buf, sizeof buf[0], 3 * k);
    }
}

/* Writes (a[i], b[i], 0) triples as Float32. */
static void put_xyz_f32(out_file *o, const float *a, const float *b, size_t n)
{
    float buf[3 * CHUNK_PARTICLES];
    for (size_t start = 0; start < n; start += CHUNK_PARTICLES) {
        size_t k = n - start < CHUNK_PARTICLES ? n - start : CHUNK_PARTICLES;
        for (size_t i = 0; i < k; i++) {
            buf[3 * i] = a[start + i];
            buf[3 * i + 1] = b[start + i];
            buf[3 * i + 2] = 0.0f;
        }
        put_le(o, buf, sizeof buf[0], 3 * k);
    }
}

/* Writes first, first+1, ..., first+n-1 as Int64. */
static void put_sequence_i64(out_file *o, int64_t first, size_t n)
{
    int64_t buf[CHUNK_PARTICLES];
    for (size_t start = 0; start < n; start += CHUNK_PARTICLES) {
        size_t k = n - start < CHUNK_PARTICLES ? n - start : CHUNK_PARTICLES;
        for (size_t i = 0; i < k; i++) {
            buf[i] = first + (int64_t)(start + i);
        }
        put_le(o, buf, sizeof buf[0], k);
    }
}

/* The parts every surge .vtp shares: XML prologue with the time_s and step field data, the opening of a
 * piece of n vertices, and after the point data the Points and one-vertex-per-point Verts tags. */
static void put_prologue(out_file *o, size_t n, const char *scalars, const char *vectors, uint64_t *offset)
{
    put_text(o, "<?xml version=\"1.0\"?>\n"
                "<VTKFile type=\"PolyData\" version=\"1.0\" byte_order=\"LittleEndian\" "
                "header_type=\"UInt64\">\n"
                "  <PolyData>\n"
                "    <FieldData>\n");
    array_tag(o, "      ", "Float64", "time_s", 0, sizeof(double), offset);
    array_tag(o, "      ", "Int64", "step", 0, sizeof(int64_t), offset);
    put_text(o, "    </FieldData>\n"
                "    <Piece NumberOfPoints=\"%zu\" NumberOfVerts=\"%zu\" NumberOfLines=\"0\" "
                "NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n"
                "      <PointData Scalars=\"%s\" Vectors=\"%s\">\n",
             n, n, scalars, vectors);
}

static void put_points_and_verts_tags(out_file *o, uint64_t n64, uint64_t *offset)
{
    put_text(o, "      </PointData>\n"
                "      <Points>\n");
    array_tag(o, "        ", "Float64", "Points", 3, 3 * 8 * n64, offset);
    put_text(o, "      </Points>\n"
                "      <Verts>\n");
    array_tag(o, "        ", "Int64", "connectivity", 1, 8 * n64, offset);
    array_tag(o, "        ", "Int64", "offsets", 1, 8 * n64, offset);
    put_text(o, "      </Verts>\n"
                "    </Piece>\n"
                "  </PolyData>\n"
                "  <AppendedData encoding=\"raw\">\n"
                "   _");
}

static void put_time_and_step(out_file *o, double time_s, int64_t step)
{
    block_header(o, sizeof(double));
    put_le(o, &time_s, sizeof time_s, 1);
    block_header(o, sizeof(int64_t));
    put_le(o, &step, sizeof step, 1);
}

/* Points (x, y, 0), the Verts blocks and the end of the file. */
static void put_points_and_verts(out_file *o, const double *x, const double *y, size_t n)
{
    block_header(o, 3 * 8 * (uint64_t)n);
    put_xyz_f64(o, x, y, n);
    block_header(o, 8 * (uint64_t)n);
    put_sequence_i64(o, 0, n);
    block_header(o, 8 * (uint64_t)n);
    put_sequence_i64(o, 1, n);
    put_text(o, "\n  </AppendedData>\n</VTKFile>\n");
}

int surge_vtp_write(const char *path, const surge_snapshot *snap, char *err, size_t err_len)
{
    if (path == NULL || snap == NULL) {
        set_err(err, err_len, "surge_vtp_write: NULL path or snapshot");
        return -1;
    }
    if (snap->count < 0 ||
        (snap->count > 0 && (snap->x_m == NULL || snap->y_m == NULL || snap->vx_mps == NULL ||
                             snap->vy_mps == NULL || snap->density_kgpm3 == NULL ||
                             snap->pressure_pa == NULL || snap->kind == NULL || snap->id == NULL))) {
        set_err(err, err_len, "cannot write '%s': invalid snapshot (count %" PRId32 ")", path, snap->count);
        return -1;
    }

    out_file o;
    if (out_open(&o, path, err, err_len) != 0) {
        return -1;
    }

    const size_t n = (size_t)snap->count;
    const uint64_t n64 = (uint64_t)n;
    uint64_t offset = 0;
    const char *in4 = "        ";
    /* the tags in the order of the binary blocks below */
    put_prologue(&o, n, "density_kgpm3", "velocity_mps", &offset);
    array_tag(&o, in4, "Float32", "velocity_mps", 3, 3 * 4 * n64, &offset);
    array_tag(&o, in4, "Float32", "density_kgpm3", 1, 4 * n64, &offset);
    array_tag(&o, in4, "Float32", "pressure_pa", 1, 4 * n64, &offset);
    array_tag(&o, in4, "UInt8", "kind", 1, n64, &offset);
    array_tag(&o, in4, "Int32", "id", 1, 4 * n64, &offset);
    put_points_and_verts_tags(&o, n64, &offset);

    /* Binary blocks: each is a UInt64 byte count followed by the little-endian data. */
    put_time_and_step(&o, snap->time_s, snap->step);
    block_header(&o, 3 * 4 * n64);
    put_xyz_f32(&o, snap->vx_mps, snap->vy_mps, n);
    block_header(&o, 4 * n64);
    put_le(&o, snap->density_kgpm3, sizeof(float), n);
    block_header(&o, 4 * n64);
    put_le(&o, snap->pressure_pa, sizeof(float), n);
    block_header(&o, n64);
    put_bytes(&o, snap->kind, n);
    block_header(&o, 4 * n64);
    put_le(&o, snap->id, sizeof(int32_t), n);
    put_points_and_verts(&o, snap->x_m, snap->y_m, n);
    return out_commit(&o, err, err_len);
}

/* The forces on the discs, written as vectors (x, y, 0) under these names */
enum { BOULDER_FORCES = 4 };
static const char *const boulder_force_names[BOULDER_FORCES] = {"fluid_force_npm", "film_force_npm",
                                                                "wall_contact_force_npm", "disc_contact_force_npm"};

static void boulder_forces(const surge_boulder_state *b, double *x[BOULDER_FORCES], double *y[BOULDER_FORCES])
{
    x[0] = b->fluid_fx_npm, y[0] = b->fluid_fy_npm;
    x[1] = b->film_fx_npm, y[1] = b->film_fy_npm;
    x[2] = b->wall_contact_fx_npm, y[2] = b->wall_contact_fy_npm;
    x[3] = b->disc_contact_fx_npm, y[3] = b->disc_contact_fy_npm;
}

int surge_vtp_write_boulders(const char *path, const surge_snapshot *snap, char *err, size_t err_len)
{
    const surge_boulder_state *b = snap ? &snap->boulders : NULL;
    if (path == NULL || b == NULL || b->count < 0) {
        set_err(err, err_len, "surge_vtp_write_boulders: NULL path or invalid snapshot");
        return -1;
    }
    out_file o;
    if (out_open(&o, path, err, err_len) != 0) {
        return -1;
    }
    const size_t n = (size_t)b->count;
    const uint64_t n64 = (uint64_t)n;
    uint64_t offset = 0;
    const char *in4 = "        ";
    put_prologue(&o, n, "radius_m", "velocity_mps", &offset);
    array_tag(&o, in4, "Float64", "velocity_mps", 3, 3 * 8 * n64, &offset);
    array_tag(&o, in4, "Float64", "omega_radps", 1, 8 * n64, &offset);
    array_tag(&o, in4, "Float64", "angle_rad", 1, 8 * n64, &offset);
    array_tag(&o, in4, "Float64", "radius_m", 1, 8 * n64, &offset);
    for (int f = 0; f < BOULDER_FORCES; f++)
        array_tag(&o, in4, "Float64", boulder_force_names[f], 3, 3 * 8 * n64, &offset);
    put_points_and_verts_tags(&o, n64, &offset);
    put_time_and_step(&o, snap->time_s, snap->step);
    block_header(&o, 3 * 8 * n64);
    put_xyz_f64(&o, b->vx_mps, b->vy_mps, n);
    block_header(&o, 8 * n64);
    put_le(&o, b->omega_radps, sizeof(double), n);
    block_header(&o, 8 * n64);
    put_le(&o, b->angle_rad, sizeof(double), n);
    block_header(&o, 8 * n64);
    put_le(&o, b->radius_m, sizeof(double), n);
    double *force_x[BOULDER_FORCES], *force_y[BOULDER_FORCES];
    boulder_forces(b, force_x, force_y);
    for (int f = 0; f < BOULDER_FORCES; f++) {
        block_header(&o, 3 * 8 * n64);
        put_xyz_f64(&o, force_x[f], force_y[f], n);
    }
    put_points_and_verts(&o, b->x_m, b->y_m, n);
    return out_commit(&o, err, err_len);
}

/* ------------------------------------------------------------------------------------------------
 * .pvd time collection
 * --------------------------------------------------------------------------------------------- */

typedef struct pvd_entry {
    double time_s;
    char *file; /* unescaped, relative to the .pvd's folder */
} pvd_entry;

struct surge_pvd {
    char *path;
    pvd_entry *entries;
    size_t count;
    size_t capacity;
};

/* Appends an entry taking ownership of file (freed on failure). */
static int pvd_push(surge_pvd *pvd, double time_s, char *file)
{
    if (pvd->count == pvd->capacity) {
        size_t capacity = pvd->capacity == 0 ? 16 : 2 * pvd->capacity;
        pvd_entry *grown = realloc(pvd->entries, capacity * sizeof *grown);
        if (grown == NULL) {
            free(file);
            return -1;
        }
        pvd->entries = grown;
        pvd->capacity = capacity;
    }
    pvd->entries[pvd->count].time_s = time_s;
    pvd->entries[pvd->count].file = file;
    pvd->count++;
    return 0;
}

/* Writes s with the five XML special characters escaped. */
static void put_xml_escaped(out_file *o, const char *s)
{
    const char *run = s;
    for (; *s != '\0'; s++) {
        const char *entity = NULL;
        switch (*s) {
        case '&': entity = "&amp;"; break;
        case '<': entity = "&lt;"; break;
        case '>': entity = "&gt;"; break;
        case '"': entity = "&quot;"; break;
        case '\'': entity = "&apos;"; break;
        default: break;
        }
        if (entity != NULL) {
            put_bytes(o, run, (size_t)(s - run));
            put_text(o, "%s", entity);
            run = s + 1;
        }
    }
    put_bytes(o, run, (size_t)(s - run));
}

static int pvd_write(const surge_pvd *pvd, char *err, size_t err_len)
{
    out_file o;
    if (out_open(&o, pvd->path, err, err_len) != 0) {
        return -1;
    }
    put_text(&o, "<?xml version=\"1.0\"?>\n"
                 "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\" "
                 "header_type=\"UInt64\">\n"
                 "  <Collection>\n");
    for (size_t i = 0; i < pvd->count; i++) {
        put_text(&o, "    <DataSet timestep=\"%.17g\" group=\"\" part=\"0\" file=\"", pvd->entries[i].time_s);
        put_xml_escaped(&o, pvd->entries[i].file);
        put_text(&o, "\"/>\n");
    }
    put_text(&o, "  </Collection>\n"
                 "</VTKFile>\n");
    return out_commit(&o, err, err_len);
}

/* Reads a whole file into a NUL-terminated buffer. Returns NULL with errno set on failure. */
static char *read_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return NULL;
    }
    size_t len = 0;
    size_t capacity = 4096;
    char *buf = malloc(capacity);
    while (buf != NULL) {
        len += fread(buf + len, 1, capacity - 1 - len, f);
        if (len < capacity - 1) {
            break; /* end of file or error, told apart below */
        }
        char *grown = realloc(buf, 2 * capacity);
        if (grown == NULL) {
            free(buf);
            buf = NULL;
            break;
        }
        buf = grown;
        capacity *= 2;
    }
    if (buf == NULL) {
        fclose(f);
        errno = ENOMEM;
        return NULL;
    }
    if (ferror(f)) {
        int saved = errno != 0 ? errno : EIO;
        free(buf);
        fclose(f);
        errno = saved;
        return NULL;
    }
    fclose(f);
    buf[len] = '\0';
    return buf;
}

static int is_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

/* Returns the end of the tag starting at tag ('>' outside quoted values), or NULL. */
static const char *tag_end(const char *tag)
{
    char quote = '\0';
    for (const char *p = tag; *p != '\0'; p++) {
        if (quote != '\0') {
            if (*p == quote) {
                quote = '\0';
            }
        } else if (*p == '"' || *p == '\'') {
            quote = *p;
        } else if (*p == '>') {
            return p;
        }
    }
    return NULL;
}

/* Finds attribute name in the tag text [begin, end); sets *value and *len to its raw (escaped) value. */
static int find_attr(const char *begin, const char *end, const char *name, const char **value, size_t *len)
{
    size_t name_len = strlen(name);
    const char *p = begin;
    while (p < end) {
        /* Skip to the next attribute name (after whitespace). */
        while (p < end && is_space(*p)) {
            p++;
        }
        const char *attr = p;
        while (p < end && !is_space(*p) && *p != '=' && *p != '/' && *p != '>') {
            p++;
        }
        size_t attr_len = (size_t)(p - attr);
        while (p < end && is_space(*p)) {
            p++;
        }
        if (p >= end || *p != '=') {
            if (attr_len == 0) {
                p++; /* a stray '/' or similar */
            }
            continue;
        }
        p++;
        while (p < end && is_space(*p)) {
            p++;
        }
        if (p >= end || (*p != '"' && *p != '\'')) {
            return -1;
        }
        char quote = *p++;
        const char *v = p;
        while (p < end && *p != quote) {
            p++;
        }
        if (p >= end) {
            return -1;
        }
        if (attr_len == name_len && memcmp(attr, name, name_len) == 0) {
            *value = v;
            *len = (size_t)(p - v);
            return 0;
        }
        p++;
    }
    return -1;
}

/* Returns a malloc'd copy of the raw attribute value with the five XML entities decoded, or NULL
 * (unknown entity or out of memory). */
static char *xml_unescape(const char *value, size_t len)
{
    static const struct {
        const char *entity;
        char c;
    } entities[] = {{"&amp;", '&'}, {"&lt;", '<'}, {"&gt;", '>'}, {"&quot;", '"'}, {"&apos;", '\''}};
    char *out = malloc(len + 1);
    if (out == NULL) {
        return NULL;
    }
    size_t n = 0;
    for (size_t i = 0; i < len;) {
        if (value[i] != '&') {
            out[n++] = value[i++];
            continue;
        }
        size_t k = 0;
        size_t count = sizeof entities / sizeof entities[0];
        for (; k < count; k++) {
            size_t elen = strlen(entities[k].entity);
            if (len - i >= elen && memcmp(value + i, entities[k].entity, elen) == 0) {
                out[n++] = entities[k].c;
                i += elen;
                break;
            }
        }
        if (k == count) {
            free(out);
            return NULL;
        }
    }
    out[n] = '\0';
    return out;
}

/* Loads the entries of the existing file with timestep < before_time_s. A missing file is fine. */
static int pvd_load(surge_pvd *pvd, double before_time_s, char *err, size_t err_len)
{
    struct stat st;
    if (stat(pvd->path, &st) == 0 && !S_ISREG(st.st_mode)) { /* a pipe or a device would be read without end */
        set_err(err, err_len, "'%s' is not a regular file (a .pvd collection was expected)", pvd->path);
        return -1;
    }
    char *text = read_file(pvd->path);
    if (text == NULL) {
        if (errno == ENOENT) {
            return 0;
        }
        set_err(err, err_len, "cannot read '%s': %s", pvd->path, strerror(errno));
        return -1;
    }
    int rc = 0;
    const char *p = text;
    while ((p = strstr(p, "<DataSet")) != NULL) {
        const char *begin = p + strlen("<DataSet");
        const char *end = tag_end(begin);
        const char *time_text = NULL;
        const char *file_text = NULL;
        size_t time_len = 0;
        size_t file_len = 0;
        if (!is_space(*begin) || end == NULL ||
            find_attr(begin, end, "timestep", &time_text, &time_len) != 0 ||
            find_attr(begin, end, "file", &file_text, &file_len) != 0) {
            set_err(err, err_len, "cannot resume '%s': malformed <DataSet> entry", pvd->path);
            rc = -1;
            break;
        }
        char number[64];
        char *number_end = NULL;
        double time_s = 0.0;
        if (time_len > 0 && time_len < sizeof number) {
            memcpy(number, time_text, time_len);
            number[time_len] = '\0';
            time_s = strtod(number, &number_end);
        }
        if (number_end == NULL || number_end == number || *number_end != '\0') {
            set_err(err, err_len, "cannot resume '%s': bad timestep \"%.*s\"", pvd->path,
                    (int)(time_len < 64 ? time_len : 64), time_text);
            rc = -1;
            break;
        }
        if (time_s < before_time_s) {
            char *file = xml_unescape(file_text, file_len);
            if (file == NULL) {
                set_err(err, err_len, "cannot resume '%s': bad file attribute or out of memory", pvd->path);
                rc = -1;
                break;
            }
            if (pvd_push(pvd, time_s, file) != 0) {
                set_err(err, err_len, "cannot resume '%s': out of memory", pvd->path);
                rc = -1;
                break;
            }
        }
        p = end + 1;
    }
    free(text);
    return rc;
}

surge_pvd *surge_pvd_open(const char *pvd_path, double resume_before_time_s, char *err, size_t err_len)
{
    if (pvd_path == NULL) {
        set_err(err, err_len, "surge_pvd_open: NULL path");
        return NULL;
    }
    surge_pvd *pvd = calloc(1, sizeof *pvd);
    if (pvd == NULL || (pvd->path = dup_string(pvd_path)) == NULL) {
        set_err(err, err_len, "cannot open '%s': out of memory", pvd_path);
        free(pvd);
        return NULL;
    }
    if ((resume_before_time_s >= 0.0 && pvd_load(pvd, resume_before_time_s, err, err_len) != 0) ||
        pvd_write(pvd, err, err_len) != 0) {
        surge_pvd_close(pvd);
        return NULL;
    }
    return pvd;
}

int surge_pvd_add(surge_pvd *pvd, double time_s, const char *relative_file, char *err, size_t err_len)
{
    if (pvd == NULL || relative_file == NULL) {
        set_err(err, err_len, "surge_pvd_add: NULL collection or file name");
        return -1;
    }
    char *file = dup_string(relative_file);
    if (file == NULL || pvd_push(pvd, time_s, file) != 0) {
        set_err(err, err_len, "cannot add to '%s': out of memory", pvd->path);
        return -1;
    }
    if (pvd_write(pvd, err, err_len) != 0) {
        pvd->count--;
        free(pvd->entries[pvd->count].file);
        return -1;
    }
    return 0;
}

void surge_pvd_close(surge_pvd *pvd)
{
    if (pvd == NULL) {
        return;
    }
    for (size_t i = 0; i < pvd->count; i++) {
        free(pvd->entries[i].file);
    }
    free(pvd->entries);
    free(pvd->path);
    free(pvd);
}

surge_pvd *surge_pvd_read(const char *pvd_path, char *err, size_t err_len)
{
    surge_pvd *pvd = calloc(1, sizeof *pvd);
    if (pvd == NULL || (pvd->path = dup_string(pvd_path)) == NULL) {
        free(pvd);
        set_err(err, err_len, "out of memory");
        return NULL;
    }
    struct stat st;
    if (stat(pvd_path, &st) != 0) {
        set_err(err, err_len, "cannot read '%s': %s", pvd_path, strerror(errno));
        surge_pvd_close(pvd);
        return NULL;
    }
    if (pvd_load(pvd, INFINITY, err, err_len) != 0) {
        surge_pvd_close(pvd);
        return NULL;
    }
    return pvd;
}

size_t surge_pvd_count(const surge_pvd *pvd) { return pvd->count; }
const char *surge_pvd_file(const surge_pvd *pvd, size_t index) { return pvd->entries[index].file; }

double surge_pvd_time_s(const surge_pvd *pvd, size_t index) { return pvd->entries[index].time_s; }

/* ------------------------------------------------------------------------------------------------
 * Reading our own .vtp files back
 * --------------------------------------------------------------------------------------------- */

typedef struct vtp_source {
    const char *path;
    const unsigned char *data;
    size_t len;
    const unsigned char *appended; /* first byte after the '_' of <AppendedData> */
} vtp_source;

/* Finds the DataArray named name, checks its type and components, and copies its block of expected_bytes. */
static int vtp_array(const vtp_source *v, const char *name, const char *type, int components, void *out,
                     size_t expected_bytes, char *err, size_t err_len)
{
    char needle[96];
    snprintf(needle, sizeof needle, "Name=\"%s\"", name);
    const char *text = (const char *)v->data;
    const char *hit = strstr(text, needle);
    const char *begin = hit ? hit : NULL;
    while (begin && begin > text && *begin != '<')
        begin--;
    const char *end = begin ? tag_end(begin) : NULL;
    const char *value = NULL;
    size_t len = 0;
    if (!end || strncmp(begin, "<DataArray", 10) != 0) {
        set_err(err, err_len, "%s: no DataArray named %s (not a surge snapshot?)", v->path, name);
        return -1;
    }
    if (find_attr(begin, end, "type", &value, &len) != 0 || len != strlen(type) || strncmp(value, type, len) != 0) {
        set_err(err, err_len, "%s: array %s is not of type %s", v->path, name, type);
        return -1;
    }
    if (components > 1 && (find_attr(begin, end, "NumberOfComponents", &value, &len) != 0 ||
                           strtol(value, NULL, 10) != components)) {
        set_err(err, err_len, "%s: array %s does not have %d components", v->path, name, components);
        return -1;
    }
    if (find_attr(begin, end, "offset", &value, &len) != 0) {
        set_err(err, err_len, "%s: array %s has no offset", v->path, name);
        return -1;
    }
    const unsigned long long offset = strtoull(value, NULL, 10);
    const size_t available = v->len - (size_t)(v->appended - v->data);
    uint64_t bytes = 0;
    /* every comparison is written so that a huge offset read from a corrupt file cannot wrap around */
    if (offset > available || available - offset < 8 ||
        (memcpy(&bytes, v->appended + offset, 8), bytes != expected_bytes) || available - offset - 8 < bytes) {
        set_err(err, err_len, "%s: array %s is truncated or has the wrong size", v->path, name);
        return -1;
    }
    memcpy(out, v->appended + offset + 8, expected_bytes);
    return 0;
}

/* What a point takes in the arrays each reader copies out: the particles' Points (3 Float64), velocity_mps (3 Float32),
 * density_kgpm3, pressure_pa, kind and id; the boulders' Points, velocity_mps (3 Float64), omega_radps, angle_rad and
 * radius_m. The file holds at least that much per point, and an 8-byte size before each of those arrays. */
enum { PARTICLE_POINT_BYTES = 3 * 8 + 3 * 4 + 4 + 4 + 1 + 4, PARTICLE_ARRAYS = 6 };
enum { BOULDER_POINT_BYTES = 3 * 8 + 3 * 8 + 8 + 8 + 8, BOULDER_ARRAYS = 5 };

/* Loads a .vtp written by surge and checks its header: v (its data to free by the caller) and the number of points,
 * or -1 with err naming the file. A point count the appended data cannot hold, at point_bytes a point and `arrays`
 * 8-byte sizes, is refused before anything is allocated for it. */
static int vtp_open(const char *path, vtp_source *v, int32_t *count, long long point_bytes, int arrays, char *err,
                    size_t err_len)
{
    if (!host_is_little_endian()) {
        set_err(err, err_len, "reading snapshots needs a little-endian machine");
        return -1;
    }
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        set_err(err, err_len, "cannot read '%s': %s", path, strerror(errno));
        return -1;
    }
    struct stat st;
    if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) { /* a folder's "size" sent malloc to 2^63 (D8) */
        fclose(f);
        set_err(err, err_len, "'%s' is not a regular file (a snapshot .vtp was expected)", path);
        return -1;
    }
    unsigned char *data = NULL;
    long size = -1;
    if (fseek(f, 0, SEEK_END) == 0 && (size = ftell(f)) >= 0 && fseek(f, 0, SEEK_SET) == 0 &&
        (data = malloc((size_t)size + 1)) != NULL && fread(data, 1, (size_t)size, f) != (size_t)size) {
        free(data);
        data = NULL;
    }
    fclose(f);
    if (data == NULL) {
        set_err(err, err_len, "cannot read '%s'", path);
        return -1;
    }
    data[size] = '\0';
    *v = (vtp_source){path, data, (size_t)size, NULL};
    const char *marker = strstr((const char *)data, "<AppendedData encoding=\"raw\">");
    const char *underscore = marker ? strchr(marker, '_') : NULL;
    const char *pieces = strstr((const char *)data, "<Piece ");
    const char *value = NULL;
    size_t len = 0;
    if (!underscore || !pieces || strncmp((const char *)data, "<?xml", 5) != 0 ||
        !strstr((const char *)data, "header_type=\"UInt64\"")) {
        set_err(err, err_len, "%s: not a surge snapshot (VTK PolyData with raw appended data)", path);
    } else if (find_attr(pieces + 6, tag_end(pieces), "NumberOfPoints", &value, &len) != 0 ||
               strtol(value, NULL, 10) < 0 || strtol(value, NULL, 10) > INT32_MAX) {
        set_err(err, err_len, "%s: bad NumberOfPoints", path);
    } else if (strtol(value, NULL, 10) * point_bytes + 8 * arrays > size - (underscore + 1 - (const char *)data)) {
        set_err(err, err_len, "%s: bad NumberOfPoints %ld: the file holds %ld bytes, too few for that many points "
                "(%lld bytes each at least)", path, strtol(value, NULL, 10), size, point_bytes);
    } else {
        v->appended = (const unsigned char *)underscore + 1;
        *count = (int32_t)strtol(value, NULL, 10);
        return 0;
    }
    free(data);
    v->data = NULL;
    return -1;
}

int surge_vtp_read(const char *path, surge_snapshot *snap, char *err, size_t err_len)
{
    vtp_source v;
    int32_t count = 0;
    if (vtp_open(path, &v, &count, PARTICLE_POINT_BYTES, PARTICLE_ARRAYS, err, err_len) != 0)
        return -1;
    int rc = -1;
    if (surge_snapshot_reserve(snap, count) != 0) {
        set_err(err, err_len, "%s: out of memory", path);
    } else {
        const size_t n = (size_t)snap->count;
        double *points = malloc(3 * 8 * n + 8);
        float *velocity = malloc(3 * 4 * n + 4);
        int64_t step = 0;
        if (points && velocity &&
            vtp_array(&v, "time_s", "Float64", 1, &snap->time_s, 8, err, err_len) == 0 &&
            vtp_array(&v, "step", "Int64", 1, &step, 8, err, err_len) == 0 &&
            vtp_array(&v, "Points", "Float64", 3, points, 3 * 8 * n, err, err_len) == 0 &&
            vtp_array(&v, "velocity_mps", "Float32", 3, velocity, 3 * 4 * n, err, err_len) == 0 &&
            vtp_array(&v, "density_kgpm3", "Float32", 1, snap->density_kgpm3, 4 * n, err, err_len) == 0 &&
            vtp_array(&v, "pressure_pa", "Float32", 1, snap->pressure_pa, 4 * n, err, err_len) == 0 &&
            vtp_array(&v, "kind", "UInt8", 1, snap->kind, n, err, err_len) == 0 &&
            vtp_array(&v, "id", "Int32", 1, snap->id, 4 * n, err, err_len) == 0) {
            for (size_t i = 0; i < n; i++) {
                snap->x_m[i] = points[3 * i];
                snap->y_m[i] = points[3 * i + 1];
                snap->vx_mps[i] = velocity[3 * i];
                snap->vy_mps[i] = velocity[3 * i + 1];
            }
            snap->step = step;
            snap->dt_s = 0;
            snap->boulders.count = 0; /* surge_vtp_read_boulders adds them */
            rc = 0;
        } else if (!points || !velocity) {
            set_err(err, err_len, "%s: out of memory", path);
        }
        free(points);
        free(velocity);
    }
    free((void *)v.data);
    return rc;
}

/* The forces on the discs into b, NaN where the file has none of them (written before they were); scratch holds 3
 * doubles a disc */
static int read_boulder_forces(const vtp_source *v, surge_boulder_state *b, double *scratch, char *err,
                               size_t err_len)
{
    double *force_x[BOULDER_FORCES], *force_y[BOULDER_FORCES];
    boulder_forces(b, force_x, force_y);
    for (int f = 0; f < BOULDER_FORCES; f++) {
        char needle[64];
        snprintf(needle, sizeof needle, "Name=\"%s\"", boulder_force_names[f]);
        const int present = strstr((const char *)v->data, needle) != NULL;
        if (present && vtp_array(v, boulder_force_names[f], "Float64", 3, scratch, 3 * 8 * (size_t)b->count, err,
                                 err_len) != 0)
            return -1;
        for (int32_t i = 0; i < b->count; i++) {
            force_x[f][i] = present ? scratch[3 * i] : NAN;
            force_y[f][i] = present ? scratch[3 * i + 1] : NAN;
        }
    }
    return 0;
}

int surge_vtp_read_boulders(const char *path, surge_snapshot *snap, char *err, size_t err_len)
{
    vtp_source v;
    int32_t count = 0;
    if (vtp_open(path, &v, &count, BOULDER_POINT_BYTES, BOULDER_ARRAYS, err, err_len) != 0)
        return -1;
    int rc = -1;
    surge_boulder_state *b = &snap->boulders;
    double *points = NULL, *velocity = NULL;
    if (surge_snapshot_reserve_boulders(snap, count) != 0 ||
        !(points = malloc(3 * 8 * (size_t)count + 8)) || !(velocity = malloc(3 * 8 * (size_t)count + 8))) {
        set_err(err, err_len, "%s: out of memory", path);
    } else if (vtp_array(&v, "Points", "Float64", 3, points, 3 * 8 * (size_t)count, err, err_len) == 0 &&
               vtp_array(&v, "velocity_mps", "Float64", 3, velocity, 3 * 8 * (size_t)count, err, err_len) == 0 &&
               vtp_array(&v, "omega_radps", "Float64", 1, b->omega_radps, 8 * (size_t)count, err, err_len) == 0 &&
               vtp_array(&v, "angle_rad", "Float64", 1, b->angle_rad, 8 * (size_t)count, err, err_len) == 0 &&
               vtp_array(&v, "radius_m", "Float64", 1, b->radius_m, 8 * (size_t)count, err, err_len) == 0) {
        for (int32_t i = 0; i < count; i++) {
            b->x_m[i] = points[3 * i];
            b->y_m[i] = points[3 * i + 1];
            b->vx_mps[i] = velocity[3 * i];
            b->vy_mps[i] = velocity[3 * i + 1];
        }
        rc = read_boulder_forces(&v, b, velocity, err, err_len);
    }
    free(points);
    free(velocity);
    free((void *)v.data);
    return rc;
}
