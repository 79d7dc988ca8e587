/* Checkpoints: the resolved parameters and the fluid state in its current (cell-sorted) order, so that a
 * restarted run repeats the uninterrupted one bit for bit. Host byte order and native real size (recorded): a
 * checkpoint restarts a run on the same kind of machine, it is not an exchange format.
 *
 * Layout: "SURGECK1" | u32 version | u32 sizeof(real) | u64 params length | params text |
 *         i64 step | f64 time_s | f64 dt_s | f64 first_dt_s | i32 count | i32 wall_count |
 *         fluid x[f64] y[f64] vx[real] vy[real] rho[real] id[i32] |
 *         (version 3) u32 lists built | fluid x_build[f64] y_build[f64] (the neighbour lists' build positions) |
 *         (version 2 on, when the scene has boulders) boulders x y angle vx vy omega [f64 each] |
 *             (version 4) angle at the last neighbour-list build [f64 each] |
 *             i32 contact count | keys[i64] lambda_n[f64] lambda_t[f64] (the contact solver's warm start) |
 *         (version 3, boulders) wall x_build[f64] y_build[f64] by wall id |
 *         (version 5 on) the scheme's own state, where it has one (the implicit scheme's:
 *             scheme/implicit/implicit_checkpoint.c) |
 *         u64 state hash | (version 4) u64 FNV-1a of every byte before it, then the end of the file
 * The version 4 checksum covers what the state hash does not (the parameters, dt, first_dt, build positions, the
 * warm start): a checkpoint edited or damaged anywhere is refused, and so are bytes after its end. Versions 1 (no
 * boulder block), 2 and 3 are still read: 1 and 2 build the lists afresh at the first step, so the restarted run
 * agrees with the saved one to round-off, not bit for bit; so does an implicit run from version 5, which builds its
 * multigrid hierarchies afresh, from version 6, whose rest-density solve starts from 0 at the first step, and from
 * version 7 with boulders, whose first step had no disc-coupling limit; an implicit run with boulders from versions 5-8,
 * whose discs were stepped after the fluid, continues with the coupled step (version 9). A scene from versions 1-9 is
 * built with the fluid sites it had in gaps too narrow beside a disc, which version 10 leaves out; a run from versions
 * 1-10 continues without the pressure between discs and walls (contacts.solid_pressure 0), as it was run, and one from
 * versions 1-11 without Anderson's acceleration of the implicit scheme's passes (implicit.disc_pressure_history 0), and
 * one from versions 1-12 without the implicit scheme's scan for the free surface (implicit.surface_scan_dp 0). */
#define _POSIX_C_SOURCE 200809L
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sim_internal.h"
#include "surge/platform.h"
#include "boulders/boulders.h"
#include "boundaries/boundary.h"
#include "neighbours/neighbours.h"
#include "scene/scene.h"

#define CHECKPOINT_MAGIC "SURGECK1"
#define CHECKPOINT_VERSION 13u

/* The least a checkpoint of this version holds with a parameter block of plen bytes and `fluid` fluid particles: the
 * header, the clock and counts, the particles' fields, (version 3 on) their neighbour-list build positions, the state
 * hash and (version 4 on) the checksum. The scheme's own state comes on top, and the boulders' (boulder_bytes). */
static long long checkpoint_bytes(uint32_t version, uint64_t plen, long long fluid)
{
    const long long per_particle = (long long)fields_checkpoint_bytes() + (version >= 3 ? 2 * 8 : 0);
    return 8 + 4 + 4 + 8 + (long long)plen + 4 * 8 + 2 * 4 + fluid * per_particle + (version >= 3 ? 4 : 0) + 8 +
           (version >= 4 ? 8 : 0);
}

/* What a scene with `discs` boulders and `walls` wall particles adds to that: each disc's state, (version 4 on) its
 * orientation at the last list build, the contact count and (version 3 on) every wall particle's build position */
#define COUNT_DISC_FIELD(name, meaning) +1
static long long boulder_bytes(uint32_t version, long long discs, long long walls)
{
    if (discs == 0 || version < 2)
        return 0;
    const long long per_disc = 8 * (0 SURGE_DISC_STEP_FIELDS(COUNT_DISC_FIELD) + (version >= 4));
    return discs * per_disc + 4 + (version >= 3 ? 16 * walls : 0);
}
#undef COUNT_DISC_FIELD

static int write_all(FILE *f, const void *data, size_t len) { return fwrite(data, 1, len, f) == len ? 0 : -1; }

/* FNV-1a of the first `length` bytes of f (read from its start); -1 when they cannot be read. */
static int file_checksum(FILE *f, long length, uint64_t *checksum)
{
    unsigned char chunk[65536];
    uint64_t h = 14695981039346656037ull;
    if (fseek(f, 0, SEEK_SET) != 0)
        return -1;
    for (long done = 0; done < length;) {
        const size_t want = (size_t)(length - done < (long)sizeof chunk ? length - done : (long)sizeof chunk);
        if (fread(chunk, 1, want, f) != want)
            return -1;
        for (size_t i = 0; i < want; i++) {
            h ^= chunk[i];
            h *= 1099511628211ull;
        }
        done += (long)want;
    }
    *checksum = h;
    return 0;
}
static int read_all(FILE *f, void *data, size_t len) { return fread(data, 1, len, f) == len ? 0 : -1; }

/* The wall particles' build positions by id (boulder scenes: the walls' order at restart follows them). */
static int write_wall_build_positions(FILE *f, const surge_sim *sim)
{
    const size_t w = (size_t)sim->wall_count;
    if (sim->boulders.count == 0)
        return 0;
    double *by_id = malloc((2 * w + 1) * sizeof *by_id);
    if (!by_id)
        return -1;
    for (size_t k = 0; k < w; k++) {
        by_id[sim->id[k]] = sim->neighbours.x_build[k];
        by_id[w + (size_t)sim->id[k]] = sim->neighbours.y_build[k];
    }
    const int rc = write_all(f, by_id, 2 * w * sizeof *by_id);
    free(by_id);
    return rc;
}

static int read_wall_build_positions(FILE *f, surge_sim *sim)
{
    const size_t w = (size_t)sim->wall_count;
    if (sim->boulders.count == 0)
        return 0;
    double *by_id = malloc((2 * w + 1) * sizeof *by_id);
    if (!by_id || read_all(f, by_id, 2 * w * sizeof *by_id)) {
        free(by_id);
        return -1;
    }
    /* outside the state hash: each must lie where a wall particle can be, the cell grid's extent give or take its
     * own size (boulder particles may sit a period away from the grid between builds) */
    const cell_grid *g = &sim->grid;
    const double width = g->ncx * g->cell_w, height = g->ncy * g->cell_h;
    int rc = 0;
    for (size_t k = 0; k < w; k++) {
        const double x = by_id[sim->id[k]], y = by_id[w + (size_t)sim->id[k]];
        sim->neighbours.x_build[k] = x;
        sim->neighbours.y_build[k] = y;
        rc |= !(x >= g->x0 - width && x <= g->x0 + 2 * width && y >= g->y0 - height && y <= g->y0 + 2 * height);
    }
    free(by_id);
    return rc ? -1 : 0;
}

static int write_boulders(FILE *f, const boulder_set *b)
{
    const size_t n = (size_t)b->count * sizeof(double);
    if (b->count == 0)
        return 0;
    const int32_t contacts = contact_solver_cache_count(b->contacts);
    int64_t *keys = malloc((size_t)(contacts + 1) * sizeof *keys);
    double *lambda_n = malloc((size_t)(contacts + 1) * sizeof *lambda_n);
    double *lambda_t = malloc((size_t)(contacts + 1) * sizeof *lambda_t);
    int rc = -1;
    if (keys && lambda_n && lambda_t) {
        contact_solver_cache_get(b->contacts, keys, lambda_n, lambda_t);
        rc = 0;
#define WRITE_DISC(name, meaning) rc |= write_all(f, b->name, n);
        SURGE_DISC_STEP_FIELDS(WRITE_DISC)
#undef WRITE_DISC
        rc |= write_all(f, b->angle_build, n) |
             write_all(f, &contacts, 4) |
             write_all(f, keys, (size_t)contacts * 8) | write_all(f, lambda_n, (size_t)contacts * 8) |
             write_all(f, lambda_t, (size_t)contacts * 8);
    }
    free(keys);
    free(lambda_n);
    free(lambda_t);
    return rc;
}

/* version: the checkpoint's (4 on: the orientations at the last neighbour-list build follow the state); end: where
 * the state hash starts at the latest (the file's size less the hash and the checksum). -1, or -2 when the contact
 * count is more than the rest of the file can hold (*contact_count says it) */
static int read_boulders(FILE *f, boulder_set *b, uint32_t version, long long end, int32_t *contact_count)
{
    const size_t n = (size_t)b->count * sizeof(double);
    if (b->count == 0)
        return 0;
    int32_t contacts = 0;
#define READ_DISC(name, meaning)                                                                                      \
    if (read_all(f, b->name, n))                                                                                      \
        return -1;
    SURGE_DISC_STEP_FIELDS(READ_DISC)
#undef READ_DISC
    if (version < 4)
        memcpy(b->angle_build, b->angle, n);
    else if (read_all(f, b->angle_build, n))
        return -1;
    for (int i = 0; i < b->count; i++) /* outside the state hash */
        if (!isfinite(b->angle_build[i]))
            return -1;
    if (read_all(f, &contacts, 4) || contacts < 0 || contacts > 64 * b->count + 1024)
        return -1;
    const long here = ftell(f);
    *contact_count = contacts;
    if (here < 0 || (long long)contacts * (8 + 8 + 8) > end - here)
        return -2; /* refused before anything is allocated for them */
    int64_t *keys = malloc((size_t)(contacts + 1) * sizeof *keys);
    double *lambda_n = malloc((size_t)(contacts + 1) * sizeof *lambda_n);
    double *lambda_t = malloc((size_t)(contacts + 1) * sizeof *lambda_t);
    int rc = -1;
    if (keys && lambda_n && lambda_t && !read_all(f, keys, (size_t)contacts * 8) &&
        !read_all(f, lambda_n, (size_t)contacts * 8) && !read_all(f, lambda_t, (size_t)contacts * 8)) {
        /* the warm start is outside the state hash: check it is what the solver wrote (sorted keys, which it
         * searches by bisection; finite impulses; no pulling normal impulse) */
        int valid = 1;
        for (int32_t k = 0; k < contacts && valid; k++)
            valid = (k == 0 || keys[k] > keys[k - 1]) && isfinite(lambda_n[k]) && isfinite(lambda_t[k]) &&
                    lambda_n[k] >= 0;
        rc = valid ? contact_solver_cache_set(b->contacts, contacts, keys, lambda_n, lambda_t) : -1;
    }
    free(keys);
    free(lambda_n);
    free(lambda_t);
    return rc;
}

int surge_sim_checkpoint_write(const surge_sim *sim, const char *path, char *err, size_t err_len)
{
    char *params_text = NULL;
    size_t params_len = 0;
    FILE *mem = open_memstream(&params_text, &params_len);
    if (!mem) {
        snprintf(err, err_len, "out of memory writing checkpoint");
        return -1;
    }
    surge_params_write(&sim->params, mem);
    if (fclose(mem) != 0 || params_text == NULL) {
        snprintf(err, err_len, "out of memory writing checkpoint");
        free(params_text);
        return -1;
    }

    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s.tmp", path);
    FILE *f = surge_fopen_waiting(tmp, "wb+"); /* read back for the checksum */
    if (!f) {
        snprintf(err, err_len, "cannot write checkpoint '%s': %s", tmp, strerror(errno));
        free(params_text);
        return -1;
    }
    const uint32_t version = CHECKPOINT_VERSION, real_size = sizeof(real);
    const uint64_t plen = params_len;
    const size_t w = (size_t)sim->wall_count, nf = (size_t)(sim->count - sim->wall_count);
    const uint64_t hash = surge_sim_state_hash(sim);
    const uint32_t lists_built = (uint32_t)sim->neighbours.valid;
    int rc = write_all(f, CHECKPOINT_MAGIC, 8) | write_all(f, &version, 4) | write_all(f, &real_size, 4) |
             write_all(f, &plen, 8) | write_all(f, params_text, params_len) |
             write_all(f, &sim->step, 8) | write_all(f, &sim->time_s, 8) | write_all(f, &sim->dt_s, 8) |
             write_all(f, &sim->first_dt_s, 8) | write_all(f, &sim->count, 4) | write_all(f, &sim->wall_count, 4) |
             fields_write(f, sim) |
             write_all(f, &lists_built, 4) | write_all(f, sim->neighbours.x_build + w, nf * sizeof(double)) |
             write_all(f, sim->neighbours.y_build + w, nf * sizeof(double)) |
             write_boulders(f, &sim->boulders) | write_wall_build_positions(f, sim) |
             (sim->scheme->checkpoint_write ? sim->scheme->checkpoint_write(f, sim) : 0) |
             write_all(f, &hash, 8);
    free(params_text);
    uint64_t checksum = 0;
    const long length = rc == 0 && fflush(f) == 0 ? ftell(f) : -1;
    rc |= length < 0 || file_checksum(f, length, &checksum) != 0 || fseek(f, 0, SEEK_END) != 0 ||
          write_all(f, &checksum, 8) != 0;
    /* on disk before it replaces the previous checkpoint, so a crash leaves one of the two whole */
    rc |= fflush(f) != 0 || fsync(fileno(f)) != 0;
    if (fclose(f) != 0 || rc != 0 || rename(tmp, path) != 0) {
        snprintf(err, err_len, "cannot write checkpoint '%s': %s", path, strerror(errno));
        remove(tmp);
        return -1;
    }
    return 0;
}

/* The particle counts that follow the parameter block (f is left where it was), checked against the file's size: a
 * checkpoint holds every fluid particle's fields (checkpoint_bytes), so counts the file cannot hold are refused before
 * anything is built. 0, or -1 with err naming the file, the field and the size. */
static int read_counts(FILE *f, const char *path, long long file_bytes, uint32_t version, uint64_t plen,
                       int32_t *count, int32_t *wall_count, char *err, size_t err_len)
{
    const long here = ftell(f);
    unsigned char clock[40];
    if (here < 0 || read_all(f, clock, sizeof clock) || fseek(f, here, SEEK_SET) != 0) {
        snprintf(err, err_len, "%s: truncated checkpoint (it ends before the particle counts)", path);
        return -1;
    }
    memcpy(count, clock + 32, 4);
    memcpy(wall_count, clock + 36, 4);
    if (*count < 0 || *wall_count < 0 || *wall_count > *count ||
        checkpoint_bytes(version, plen, (long long)*count - *wall_count) > file_bytes) {
        snprintf(err, err_len, "%s: bad particle count %d (walls %d): the file holds %lld bytes, too few for that many "
                 "particles", path, *count, *wall_count, file_bytes);
        return -1;
    }
    return 0;
}

/* The scene the parameters describe, counted before it is built (scene_count), against the checkpoint's counts and
 * size: the fluid lattice of a scene without boulders is its fluid, so a checkpoint of it holds every site's
 * particle; the boulders may cover some of the lattice and add wall particles. 0, or -1 with err. */
static int scene_fits(const surge_params *params, const char *path, long long file_bytes, uint32_t version,
                      uint64_t plen, int32_t count, int32_t wall_count, char *err, size_t err_len)
{
    char msg[512];
    long long box_walls = 0, sites = 0;
    if (surge_params_validate(params, msg, sizeof msg) != 0 || scene_count(params, &box_walls, &sites, msg,
                                                                           sizeof msg) != 0) {
        snprintf(err, err_len, "%s: bad parameters in checkpoint: %s", path, msg);
        return -1;
    }
    const int boulders = params->boulders.placement != SURGE_BOULDERS_NONE;
    const long long fluid = (long long)count - wall_count;
    const long long least = checkpoint_bytes(version, plen, boulders ? 0 : sites);
    if (least > file_bytes) {
        snprintf(err, err_len, "%s: its parameters describe a scene of %lld fluid particles (and %lld wall particles): "
                 "a checkpoint of it holds at least %lld bytes; the file holds %lld bytes", path, sites, box_walls,
                 least, file_bytes);
        return -1;
    }
    if (boulders ? fluid > sites || wall_count < box_walls : fluid != sites || wall_count != box_walls) {
        snprintf(err, err_len, "%s: particle counts do not match the scene its parameters describe (the checkpoint "
                 "holds %lld fluid and %d wall particles, the scene %s%lld and %s%lld)", path, fluid, wall_count,
                 boulders ? "at most " : "", sites, boulders ? "at least " : "", box_walls);
        return -1;
    }
    return 0;
}

/* The checkpoint's counts and size, for the scene's own check while it is built (check_scene) */
typedef struct checkpoint_counts {
    long long file_bytes;
    uint32_t version;
    uint64_t plen;
    int32_t count, wall_count;
} checkpoint_counts;

/* Called with the scene's exact counts, its boulders defined, before anything is allocated for its particles: they
 * must be the checkpoint's, and the file must hold the boulders' state too. 0, or -1 with err (which the loader
 * prefixes with the checkpoint's path, as every error of building its scene). */
static int check_scene(const surge_sim *sim, long long walls, long long fluid, void *user, char *err, size_t err_len)
{
    const checkpoint_counts *c = user;
    if (walls != c->wall_count || walls + fluid != c->count) {
        snprintf(err, err_len, "particle counts do not match the scene its parameters describe (the checkpoint "
                 "holds %d particles, %d of them walls; the scene %lld, %lld walls)", c->count, c->wall_count,
                 walls + fluid, walls);
        return -1;
    }
    const long long least = checkpoint_bytes(c->version, c->plen, fluid) +
                            boulder_bytes(c->version, sim->boulders.count, walls);
    if (least > c->file_bytes) {
        snprintf(err, err_len, "its scene has %d boulders and %lld wall particles: a checkpoint of it holds at least "
                 "%lld bytes; the file holds %lld bytes", sim->boulders.count, walls, least, c->file_bytes);
        return -1;
    }
    return 0;
}

/* The header: magic, version, the parameters (with the live overrides) and the scene they build, once its counts are
 * known to fit the file; NULL with err set */
static surge_sim *read_header(FILE *f, const char *path, long long file_bytes, const char *const *overrides,
                              int override_count, uint32_t *version, char *err, size_t err_len)
{
    char magic[8];
    uint32_t real_size = 0;
    uint64_t plen = 0;
    if (read_all(f, magic, 8) || memcmp(magic, CHECKPOINT_MAGIC, 8) || read_all(f, version, 4) ||
        read_all(f, &real_size, 4) || read_all(f, &plen, 8)) {
        snprintf(err, err_len, "%s: not a surge checkpoint", path);
        return NULL;
    }
    if (*version < 1 || *version > CHECKPOINT_VERSION || real_size != sizeof(real)) {
        snprintf(err, err_len, "%s: checkpoint version %u with %u-byte reals; this build reads version %u with "
                 "%zu-byte reals", path, *version, real_size, CHECKPOINT_VERSION, sizeof(real));
        return NULL;
    }
    if (plen > (1u << 20) || plen > (uint64_t)file_bytes) {
        snprintf(err, err_len, "%s: bad parameter block length %llu: the file holds %lld bytes (and a block takes "
                 "at most 1 MiB)", path, (unsigned long long)plen, file_bytes);
        return NULL;
    }
    char *text = NULL;
    if (!(text = malloc(plen + 1)) || read_all(f, text, plen)) {
        snprintf(err, err_len, "%s: truncated or corrupt parameter block", path);
        free(text);
        return NULL;
    }
    text[plen] = '\0';
    checkpoint_counts counts = {.file_bytes = file_bytes, .version = *version, .plen = plen};
    if (read_counts(f, path, file_bytes, *version, plen, &counts.count, &counts.wall_count, err, err_len) != 0) {
        free(text);
        return NULL;
    }
    surge_params params = surge_default_params();
    params.contacts.solid_pressure = *version >= 11; /* its key is in the text from version 11 on */
    if (*version < 12) /* and this one's from version 12 on */
        params.implicit.disc_pressure_history = 0;
    if (*version < 13) /* and this one's from version 13 on */
        params.implicit.surface_scan_dp = 0;
    char msg[512];
    surge_sim *sim = NULL;
    if (surge_params_load_text(&params, text, path, msg, sizeof msg) != 0)
        snprintf(err, err_len, "%s: bad parameters in checkpoint: %s", path, msg);
    else {
        int overridden = 1;
        for (int i = 0; i < override_count && overridden; i++)
            overridden = surge_params_override(&params, overrides[i], true, err, err_len) == 0;
        if (overridden && scene_fits(&params, path, file_bytes, *version, plen, counts.count, counts.wall_count, err,
                                     err_len) == 0 &&
            !(sim = sim_create_checked(&params, check_scene, &counts, *version < 10, msg, sizeof msg)))
            snprintf(err, err_len, "%s: %s", path, msg);
    }
    free(text);
    return sim;
}

/* Step, time and the particle counts, as the checkpoint holds them */
typedef struct checkpoint_clock {
    int64_t step;
    double time_s, dt_s, first_dt_s;
    int32_t count, wall_count;
    uint32_t lists_built;
    uint64_t hash;
} checkpoint_clock;

/* The state after the header, up to the state hash; -1 with err set */
static int read_state(FILE *f, surge_sim *sim, const char *path, long long file_bytes, uint32_t version,
                      checkpoint_clock *c, char *err, size_t err_len)
{
    if (read_all(f, &c->step, 8) || read_all(f, &c->time_s, 8) || read_all(f, &c->dt_s, 8) ||
        read_all(f, &c->first_dt_s, 8) || read_all(f, &c->count, 4) || read_all(f, &c->wall_count, 4) ||
        c->count != sim->count || c->wall_count != sim->wall_count) {
        snprintf(err, err_len, "%s: particle counts do not match the scene its parameters describe", path);
        return -1;
    }
    const size_t w = (size_t)c->wall_count, nf = (size_t)(c->count - c->wall_count);
    if (fields_read(f, sim)) {
        snprintf(err, err_len, "%s: truncated checkpoint", path);
        return -1;
    }
    neighbour_lists *nl = &sim->neighbours;
    if (version >= 3 && (read_all(f, &c->lists_built, 4) || read_all(f, nl->x_build + w, nf * sizeof(double)) ||
                         read_all(f, nl->y_build + w, nf * sizeof(double)))) {
        snprintf(err, err_len, "%s: truncated checkpoint", path);
        return -1;
    }
    if (version < 3) { /* no lists saved: built at the first step */
        memcpy(nl->x_build + w, sim->x + w, nf * sizeof(double));
        memcpy(nl->y_build + w, sim->y + w, nf * sizeof(double));
    }
    if (version == 1 && sim->boulders.count > 0) {
        snprintf(err, err_len, "%s: a version 1 checkpoint holds no boulder state, but its scene has boulders", path);
        return -1;
    }
    int32_t contacts = 0;
    const int boulders_read = read_boulders(f, &sim->boulders, version, file_bytes - 8 - (version >= 4 ? 8 : 0),
                                            &contacts);
    if (boulders_read == -2) {
        snprintf(err, err_len, "%s: bad contact count %d: the file holds %lld bytes, too few for that many contacts",
                 path, (int)contacts, file_bytes);
        return -1;
    }
    if (boulders_read != 0) {
        snprintf(err, err_len, "%s: truncated or corrupt boulder state", path);
        return -1;
    }
    if (version >= 3 && read_wall_build_positions(f, sim)) {
        snprintf(err, err_len, "%s: truncated or corrupt wall build positions", path);
        return -1;
    }
    if (sim->scheme->checkpoint_read && sim->scheme->checkpoint_read(f, sim, version)) {
        snprintf(err, err_len, "%s: truncated or corrupt %s-scheme state", path, sim->scheme->name);
        return -1;
    }
    if (read_all(f, &c->hash, 8)) {
        snprintf(err, err_len, "%s: truncated checkpoint", path);
        return -1;
    }
    return 0;
}

/* The end: (version 4) the checksum of every byte before it, then nothing; -1 with err set */
static int read_end(FILE *f, const char *path, uint32_t version, char *err, size_t err_len)
{
    if (version < 4) {
        if (fgetc(f) == EOF)
            return 0;
        snprintf(err, err_len, "%s: bytes after the end of the checkpoint", path);
        return -1;
    }
    const long length = ftell(f);
    uint64_t stored = 0, computed = 0;
    if (length < 0 || read_all(f, &stored, 8)) {
        snprintf(err, err_len, "%s: truncated checkpoint (no checksum)", path);
        return -1;
    }
    if (fgetc(f) != EOF) {
        snprintf(err, err_len, "%s: bytes after the end of the checkpoint", path);
        return -1;
    }
    if (file_checksum(f, length, &computed) != 0 || computed != stored) {
        snprintf(err, err_len, "%s: checksum mismatch: the checkpoint was changed or damaged after it was "
                 "written (its parameters, time step or state)", path);
        return -1;
    }
    return 0;
}

/* What the checksum cannot vouch for by itself: a clock that makes sense, fluid ids that are a permutation, the state
 * hash, build positions within reach of their particles; -1 with err set */
static int validate_state(surge_sim *sim, const char *path, const checkpoint_clock *c, char *err, size_t err_len)
{
    /* a run past its first step has a first time step (the dt-collapse check divides by it) */
    if (!(isfinite(c->time_s) && c->time_s >= 0 && isfinite(c->dt_s) && c->dt_s >= 0 && isfinite(c->first_dt_s) &&
          c->first_dt_s >= 0 && c->step >= 0) ||
        (c->step > 0 && !(c->first_dt_s > 0 && c->dt_s > 0))) {
        snprintf(err, err_len, "%s: corrupt step, time or time step (outside the state hash)", path);
        return -1;
    }
    sim->step = c->step;
    sim->time_s = c->time_s;
    sim->dt_s = c->dt_s;
    sim->first_dt_s = c->first_dt_s;
    const int32_t count = c->count, wall_count = c->wall_count;
    uint8_t *seen = calloc((size_t)(count - wall_count) + 1, 1); /* the fluid ids must be a permutation */
    if (!seen) {
        snprintf(err, err_len, "%s: out of memory", path);
        return -1;
    }
    for (int32_t i = wall_count; i < count; i++) {
        const int32_t id = sim->id[i];
        if (id < wall_count || id >= count || seen[id - wall_count]++) {
            snprintf(err, err_len, "%s: corrupt particle ids (id %d out of range or repeated)", path, (int)id);
            free(seen);
            return -1;
        }
    }
    free(seen);
    if (surge_sim_state_hash(sim) != c->hash) {
        snprintf(err, err_len, "%s: state hash mismatch (corrupt checkpoint)", path);
        return -1;
    }
    /* the build positions are outside the hash: each within reach of its particle (a step past skin/2 at most) */
    const neighbour_lists *nl = &sim->neighbours;
    const double allowed_m = nl->skin_m + 2.0 * sim->derived.h_m;
    for (int32_t a = wall_count; a < count; a++) {
        const double dx = sim->x[a] - nl->x_build[a], dy = sim->y[a] - nl->y_build[a];
        if (!(dx * dx + dy * dy <= allowed_m * allowed_m)) {
            snprintf(err, err_len, "%s: corrupt neighbour-list build position of particle %d (%g m from it)", path,
                     (int)sim->id[a], sqrt(dx * dx + dy * dy));
            return -1;
        }
    }
    return 0;
}

surge_sim *surge_sim_checkpoint_read(const char *path, const char *const *overrides, int override_count,
                                     char *err, size_t err_len)
{
    struct stat st;
    FILE *f = NULL;
    if (stat(path, &st) == 0 && !S_ISREG(st.st_mode)) {
        snprintf(err, err_len, "'%s' is not a regular file (a checkpoint was expected)", path);
        return NULL;
    }
    if (stat(path, &st) != 0 || !(f = fopen(path, "rb"))) {
        snprintf(err, err_len, "cannot open checkpoint '%s': %s", path, strerror(errno));
        return NULL;
    }
    uint32_t version = 0;
    checkpoint_clock clock = {0};
    surge_sim *sim = read_header(f, path, (long long)st.st_size, overrides, override_count, &version, err, err_len);
    if (sim && (read_state(f, sim, path, (long long)st.st_size, version, &clock, err, err_len) != 0 ||
                read_end(f, path, version, err, err_len) != 0 || validate_state(sim, path, &clock, err, err_len) != 0)) {
        surge_sim_destroy(sim);
        sim = NULL;
    }
    if (sim && clock.lists_built && neighbours_adopt_build_positions(sim) != 0) {
        snprintf(err, err_len, "%s: out of memory for the neighbour lists", path);
        surge_sim_destroy(sim);
        sim = NULL;
    }
    if (sim) {
        boulders_index_particles(sim); /* the walls in the checkpoint's order */
        boundary_wall_speeds(sim, clock.time_s);
        boulders_place_particles(sim);
    }
    fclose(f);
    return sim;
}
