/* Test of surge_vtp_write, the .pvd collection and surge_snapshot_reserve/free.
 *
 * Usage: test_vtk_output DIR   (DIR must exist and be writable)
 *
 * Writes into DIR:
 *   synthetic.vtp  the synthetic snapshot below; tests/test_vtk_roundtrip.py DIR/synthetic.vtp then
 *                  decodes it and compares with the same known values.
 *   synthetic.pvd  the collection built below (final contents: see EXPECTED_PVD).
 *   empty.vtp      a snapshot with no particles.
 *
 * Known values (keep in sync with tests/test_vtk_roundtrip.py):
 *   step = 1234567890123, time_s = 12.345678901234567, 5 particles:
 *   i  x_m           y_m      vx_mps  vy_mps   density  pressure  kind  id
 *   0  -1.25         0.5      -3.5    2.25     998.5    -1250.75  0     7
 *   1  0.1           -2.75    2.25    -0.5     1000.25  0.0       1     0
 *   2  1e-300        2.5e-8   0.1     -0.1     1002.0   3.0e5     2     -1
 *   3  -123456.789   7.0e10   -1e-3   65504.0  999.875  -0.1      1     2147483647
 *   4  3.0           -1e-5    1e30    -7.0     1001.125 123.456   0     42
 *   The Float32 columns are stored as (float) of the double literals, as numpy.float32() does.
 */
#define _POSIX_C_SOURCE 200809L

#include "surge/snapshot.h"
#include "surge/vtk_output.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#define N_PARTICLES 5

static const double KNOWN_X[N_PARTICLES] = {-1.25, 0.1, 1e-300, -123456.789, 3.0};
static const double KNOWN_Y[N_PARTICLES] = {0.5, -2.75, 2.5e-8, 7.0e10, -1e-5};
static const double KNOWN_VX[N_PARTICLES] = {-3.5, 2.25, 0.1, -1e-3, 1e30};
static const double KNOWN_VY[N_PARTICLES] = {2.25, -0.5, -0.1, 65504.0, -7.0};
static const double KNOWN_RHO[N_PARTICLES] = {998.5, 1000.25, 1002.0, 999.875, 1001.125};
static const double KNOWN_P[N_PARTICLES] = {-1250.75, 0.0, 3.0e5, -0.1, 123.456};
static const uint8_t KNOWN_KIND[N_PARTICLES] = {0, 1, 2, 1, 0};
static const int32_t KNOWN_ID[N_PARTICLES] = {7, 0, -1, 2147483647, 42};
#define KNOWN_STEP INT64_C(1234567890123)
#define KNOWN_TIME 12.345678901234567

/* Final synthetic.pvd: three entries written, then resumed before t = 0.2 and one entry added. */
static const char EXPECTED_PVD[] =
    "<?xml version=\"1.0\"?>\n"
    "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
    "  <Collection>\n"
    "    <DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"synthetic_0.vtp\"/>\n"
    "    <DataSet timestep=\"0.10000000000000001\" group=\"\" part=\"0\" "
    "file=\"sub dir/a&amp;b&lt;c&gt;&quot;.vtp\"/>\n"
    "    <DataSet timestep=\"0.20000000000000001\" group=\"\" part=\"0\" file=\"synthetic.vtp\"/>\n"
    "  </Collection>\n"
    "</VTKFile>\n";

static const char EMPTY_PVD[] =
    "<?xml version=\"1.0\"?>\n"
    "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"UInt64\">\n"
    "  <Collection>\n"
    "  </Collection>\n"
    "</VTKFile>\n";

static int failures = 0;

#define CHECK(cond, err)                                                                            \
    do {                                                                                            \
        if (!(cond)) {                                                                              \
            fprintf(stderr, "FAIL %s:%d: %s (err: \"%s\")\n", __FILE__, __LINE__, #cond, (err));    \
            failures++;                                                                             \
        }                                                                                           \
    } while (0)

/* Joins dir and name into out (static size); exits on truncation. */
static void join(char *out, size_t out_len, const char *dir, const char *name)
{
    int len = snprintf(out, out_len, "%s/%s", dir, name);
    if (len < 0 || (size_t)len >= out_len) {
        fprintf(stderr, "FAIL: path too long: %s/%s\n", dir, name);
        exit(1);
    }
}

/* Reads a whole file; returns a malloc'd NUL-terminated buffer (NULL if unreadable), *len its size. */
static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (f == NULL) {
        return NULL;
    }
    size_t cap = 1 << 16;
    size_t n = 0;
    char *buf = malloc(cap);
    while (buf != NULL) {
        n += fread(buf + n, 1, cap - 1 - n, f);
        if (n < cap - 1) {
            break;
        }
        char *grown = realloc(buf, 2 * cap);
        if (grown == NULL) {
            free(buf);
            buf = NULL;
        } else {
            buf = grown;
            cap *= 2;
        }
    }
    fclose(f);
    if (buf != NULL) {
        buf[n] = '\0';
        *len = n;
    }
    return buf;
}

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

static void check_text_file(const char *path, const char *expected)
{
    size_t len = 0;
    char *text = slurp(path, &len);
    CHECK(text != NULL, path);
    if (text != NULL) {
        if (strcmp(text, expected) != 0) {
            fprintf(stderr, "FAIL: %s differs.\n--- got:\n%s--- expected:\n%s---\n", path, text, expected);
            failures++;
        }
        free(text);
    }
}

static void test_reserve(void)
{
    surge_snapshot snap = {0};
    CHECK(surge_snapshot_reserve(&snap, 3) == 0, "");
    CHECK(snap.count == 3 && snap.capacity == 3, "");
    CHECK(snap.x_m && snap.y_m && snap.vx_mps && snap.vy_mps && snap.density_kgpm3 && snap.pressure_pa &&
              snap.kind && snap.id,
          "");
    CHECK(surge_snapshot_reserve(&snap, 1) == 0 && snap.count == 1 && snap.capacity == 3, "");
    CHECK(surge_snapshot_reserve(&snap, 100) == 0 && snap.count == 100 && snap.capacity == 100, "");
    snap.id[99] = 99; /* the whole new length is usable (valgrind checks this) */
    CHECK(surge_snapshot_reserve(&snap, -1) == -1, "");
    surge_snapshot_free(&snap);
    CHECK(snap.x_m == NULL && snap.id == NULL && snap.capacity == 0, "");
    surge_snapshot_free(&snap); /* idempotent */
}

static void test_vtp(const char *dir)
{
    char path[4096];
    char tmp[4096];
    char err[512] = "";
    surge_snapshot snap = {0};
    if (surge_snapshot_reserve(&snap, N_PARTICLES) != 0) {
        fprintf(stderr, "FAIL: surge_snapshot_reserve\n");
        exit(1);
    }
    snap.step = KNOWN_STEP;
    snap.time_s = KNOWN_TIME;
    snap.dt_s = 1e-4;
    for (int i = 0; i < N_PARTICLES; i++) {
        snap.x_m[i] = KNOWN_X[i];
        snap.y_m[i] = KNOWN_Y[i];
        snap.vx_mps[i] = (float)KNOWN_VX[i];
        snap.vy_mps[i] = (float)KNOWN_VY[i];
        snap.density_kgpm3[i] = (float)KNOWN_RHO[i];
        snap.pressure_pa[i] = (float)KNOWN_P[i];
        snap.kind[i] = KNOWN_KIND[i];
        snap.id[i] = KNOWN_ID[i];
    }

    join(path, sizeof path, dir, "synthetic.vtp");
    join(tmp, sizeof tmp, dir, "synthetic.vtp.tmp");
    /* Twice: the second write replaces the first. */
    CHECK(surge_vtp_write(path, &snap, err, sizeof err) == 0, err);
    CHECK(surge_vtp_write(path, &snap, err, sizeof err) == 0, err);
    CHECK(!file_exists(tmp), tmp);

    /* Header text and exact file size (the binary part is decoded by test_vtk_roundtrip.py). */
    size_t len = 0;
    char *data = slurp(path, &len);
    CHECK(data != NULL, path);
    if (data != NULL) {
        /* strstr stops at the first NUL, which lies in the binary part after the header. */
        static const char marker[] = "<AppendedData encoding=\"raw\">\n   _";
        static const char trailer[] = "\n  </AppendedData>\n</VTKFile>\n";
        CHECK(strncmp(data, "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" "
                            "byte_order=\"LittleEndian\" header_type=\"UInt64\">",
                      strlen("<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\" version=\"1.0\" "
                             "byte_order=\"LittleEndian\" header_type=\"UInt64\">")) == 0,
              data);
        CHECK(strstr(data, "NumberOfPoints=\"5\" NumberOfVerts=\"5\"") != NULL, "");
        CHECK(strstr(data, "Name=\"velocity_mps\" NumberOfComponents=\"3\"") != NULL, "");
        CHECK(strstr(data, "Name=\"time_s\" NumberOfTuples=\"1\"") != NULL, "");
        const char *m = strstr(data, marker);
        CHECK(m != NULL, "no AppendedData marker");
        if (m != NULL) {
            size_t header_len = (size_t)(m - data) + strlen(marker);
            /* 10 blocks with UInt64 headers; time + step; per particle 24+8+8+12+4+4+1+4 bytes. */
            size_t binary_len = 10 * 8 + 8 + 8 + (size_t)N_PARTICLES * 65;
            CHECK(len == header_len + binary_len + strlen(trailer), "file size");
            CHECK(len > strlen(trailer) && memcmp(data + len - strlen(trailer), trailer, strlen(trailer)) == 0,
                  "trailer");
        }
        free(data);
    }

    /* No particles at all (NULL arrays are allowed then). */
    surge_snapshot empty = {0};
    empty.step = 0;
    join(path, sizeof path, dir, "empty.vtp");
    CHECK(surge_vtp_write(path, &empty, err, sizeof err) == 0, err);

    /* Missing directory: -1 and a message naming the path. */
    join(path, sizeof path, dir, "no_such_dir/synthetic.vtp");
    err[0] = '\0';
    CHECK(surge_vtp_write(path, &snap, err, sizeof err) == -1, "");
    CHECK(strstr(err, path) != NULL, err);
    CHECK(surge_vtp_write(path, &snap, NULL, 0) == -1, ""); /* no err buffer is fine */

    /* Target is a directory: the rename fails, the temporary file is removed. */
    join(path, sizeof path, dir, "is_a_dir");
    join(tmp, sizeof tmp, dir, "is_a_dir.tmp");
    CHECK(mkdir(path, 0777) == 0 || errno == EEXIST, path);
    err[0] = '\0';
    CHECK(surge_vtp_write(path, &snap, err, sizeof err) == -1, "");
    CHECK(strstr(err, path) != NULL, err);
    CHECK(!file_exists(tmp), tmp);
    rmdir(path);

    /* Invalid snapshot. */
    surge_snapshot bad = {0};
    bad.count = 3;
    CHECK(surge_vtp_write(path, &bad, err, sizeof err) == -1, "");

    surge_snapshot_free(&snap);
}

static void test_pvd(const char *dir)
{
    char path[4096];
    char err[512] = "";

    join(path, sizeof path, dir, "synthetic.pvd");
    remove(path);

    /* Resuming with no file yet gives an empty collection. */
    surge_pvd *pvd = surge_pvd_open(path, 1.0, err, sizeof err);
    CHECK(pvd != NULL, err);
    surge_pvd_close(pvd);
    check_text_file(path, EMPTY_PVD);

    pvd = surge_pvd_open(path, -1.0, err, sizeof err);
    CHECK(pvd != NULL, err);
    if (pvd == NULL) {
        return;
    }
    check_text_file(path, EMPTY_PVD);
    CHECK(surge_pvd_add(pvd, 0.0, "synthetic_0.vtp", err, sizeof err) == 0, err);
    CHECK(surge_pvd_add(pvd, 0.1, "sub dir/a&b<c>\".vtp", err, sizeof err) == 0, err);
    CHECK(surge_pvd_add(pvd, 0.1 + 0.2, "synthetic_2.vtp", err, sizeof err) == 0, err);
    surge_pvd_close(pvd);
    check_text_file(path,
                    "<?xml version=\"1.0\"?>\n"
                    "<VTKFile type=\"Collection\" version=\"1.0\" byte_order=\"LittleEndian\" "
                    "header_type=\"UInt64\">\n"
                    "  <Collection>\n"
                    "    <DataSet timestep=\"0\" group=\"\" part=\"0\" file=\"synthetic_0.vtp\"/>\n"
                    "    <DataSet timestep=\"0.10000000000000001\" group=\"\" part=\"0\" "
                    "file=\"sub dir/a&amp;b&lt;c&gt;&quot;.vtp\"/>\n"
                    "    <DataSet timestep=\"0.30000000000000004\" group=\"\" part=\"0\" "
                    "file=\"synthetic_2.vtp\"/>\n"
                    "  </Collection>\n"
                    "</VTKFile>\n");

    /* Restart between entries 2 and 3: entry 3 is dropped, a new one appended. */
    pvd = surge_pvd_open(path, 0.2, err, sizeof err);
    CHECK(pvd != NULL, err);
    if (pvd == NULL) {
        return;
    }
    CHECK(surge_pvd_add(pvd, 0.2, "synthetic.vtp", err, sizeof err) == 0, err);
    surge_pvd_close(pvd);
    check_text_file(path, EXPECTED_PVD);

    /* Resuming from the resumed file keeps it as it is. */
    pvd = surge_pvd_open(path, 5.0, err, sizeof err);
    CHECK(pvd != NULL, err);
    surge_pvd_close(pvd);
    check_text_file(path, EXPECTED_PVD);

    char tmp[4096];
    join(tmp, sizeof tmp, dir, "synthetic.pvd.tmp");
    CHECK(!file_exists(tmp), tmp);

    /* Many entries (the array grows). */
    char many[4096];
    join(many, sizeof many, dir, "many.pvd");
    pvd = surge_pvd_open(many, -1.0, err, sizeof err);
    CHECK(pvd != NULL, err);
    for (int i = 0; pvd != NULL && i < 100; i++) {
        char name[32];
        snprintf(name, sizeof name, "f_%d.vtp", i);
        CHECK(surge_pvd_add(pvd, 0.01 * i, name, err, sizeof err) == 0, err);
    }
    surge_pvd_close(pvd);
    pvd = surge_pvd_open(many, 0.505, err, sizeof err); /* keeps i = 0..50 */
    CHECK(pvd != NULL, err);
    surge_pvd_close(pvd);
    size_t len = 0;
    char *text = slurp(many, &len);
    CHECK(text != NULL, many);
    if (text != NULL) {
        CHECK(strstr(text, "file=\"f_50.vtp\"") != NULL, "f_50 kept");
        CHECK(strstr(text, "file=\"f_51.vtp\"") == NULL, "f_51 dropped");
        free(text);
    }
    remove(many);

    /* Malformed file: resuming fails with a message. */
    char bad[4096];
    join(bad, sizeof bad, dir, "bad.pvd");
    FILE *f = fopen(bad, "w");
    CHECK(f != NULL, bad);
    if (f != NULL) {
        fputs("<VTKFile type=\"Collection\"><Collection>\n"
              "<DataSet timestep=\"abc\" file=\"x.vtp\"/>\n</Collection></VTKFile>\n",
              f);
        fclose(f);
        err[0] = '\0';
        pvd = surge_pvd_open(bad, 1.0, err, sizeof err);
        CHECK(pvd == NULL, "malformed file accepted");
        surge_pvd_close(pvd);
        CHECK(strstr(err, bad) != NULL, err);
        remove(bad);
    }

    /* Missing directory. */
    join(path, sizeof path, dir, "no_such_dir/x.pvd");
    err[0] = '\0';
    pvd = surge_pvd_open(path, -1.0, err, sizeof err);
    CHECK(pvd == NULL, "");
    CHECK(strstr(err, path) != NULL, err);
    surge_pvd_close(pvd);
}

/* The boulders' file: state and per-disc forces read back bit for bit; a file written before the forces existed (their
 * arrays renamed here) reads with the forces NaN */
static void test_boulders(const char *dir)
{
    char path[4096];
    char err[512] = "";
    join(path, sizeof path, dir, "boulders.vtp");
    surge_snapshot snap = {0}, back = {0};
    CHECK(surge_snapshot_reserve_boulders(&snap, 2) == 0, "");
    surge_boulder_state *b = &snap.boulders;
    double *const forces[] = {b->fluid_fx_npm, b->fluid_fy_npm, b->film_fx_npm, b->film_fy_npm,
                              b->wall_contact_fx_npm, b->wall_contact_fy_npm, b->disc_contact_fx_npm,
                              b->disc_contact_fy_npm};
    for (int i = 0; i < 2; i++) {
        b->x_m[i] = 1.5 + i, b->y_m[i] = 0.25 * i, b->angle_rad[i] = -0.5 * i, b->vx_mps[i] = 0.1 / 3;
        b->vy_mps[i] = -2e-7 * i, b->omega_radps[i] = 1e-300, b->radius_m[i] = 0.1 + i;
        for (int f = 0; f < 8; f++)
            forces[f][i] = (f + 1) * (i ? -1.0 / 7 : 1e5 / 3);
    }
    b->fluid_fx_npm[1] = NAN; /* not known before a first step */
    CHECK(surge_vtp_write_boulders(path, &snap, err, sizeof err) == 0, err);
    CHECK(surge_vtp_read_boulders(path, &back, err, sizeof err) == 0, err);
    const surge_boulder_state *r = &back.boulders;
    const double *const read[] = {r->fluid_fx_npm, r->fluid_fy_npm, r->film_fx_npm, r->film_fy_npm,
                                  r->wall_contact_fx_npm, r->wall_contact_fy_npm, r->disc_contact_fx_npm,
                                  r->disc_contact_fy_npm};
    int same = r->count == 2;
    for (int i = 0; same && i < 2; i++) {
        same &= r->x_m[i] == b->x_m[i] && r->y_m[i] == b->y_m[i] && r->vx_mps[i] == b->vx_mps[i] &&
                r->omega_radps[i] == b->omega_radps[i] && r->radius_m[i] == b->radius_m[i];
        for (int f = 0; f < 8; f++)
            same &= read[f][i] == forces[f][i] || (isnan(read[f][i]) && isnan(forces[f][i]));
    }
    CHECK(same, "the boulders' state and forces read back");
    size_t len = 0;
    char *text = slurp(path, &len);
    CHECK(text != NULL, path);
    char *components = text ? strstr(text, "Name=\"film_force_npm\" NumberOfComponents=\"3\"") : NULL;
    CHECK(components != NULL, "the film force's tag");
    if (components) { /* a force array of the wrong shape is refused, named */
        components[strlen("Name=\"film_force_npm\" NumberOfComponents=\"")] = '2';
        FILE *f = fopen(path, "wb");
        CHECK(f && fwrite(text, 1, len, f) == len && fclose(f) == 0, path);
        CHECK(surge_vtp_read_boulders(path, &back, err, sizeof err) == -1 && strstr(err, "film_force_npm") &&
                  strstr(err, "boulders.vtp"),
              err);
        components[strlen("Name=\"film_force_npm\" NumberOfComponents=\"")] = '3';
    }
    if (text) {
        for (char *hit = text; (hit = strstr(hit, "_force_npm\"")) != NULL; hit++)
            hit[0] = 'X'; /* another array's name: the forces are gone */
        FILE *f = fopen(path, "wb");
        CHECK(f && fwrite(text, 1, len, f) == len && fclose(f) == 0, path);
        free(text);
        CHECK(surge_vtp_read_boulders(path, &back, err, sizeof err) == 0, err);
        int all_nan = back.boulders.count == 2 && back.boulders.x_m[1] == 2.5;
        for (int i = 0; all_nan && i < 2; i++)
            all_nan &= isnan(back.boulders.fluid_fx_npm[i]) && isnan(back.boulders.wall_contact_fy_npm[i]) &&
                       isnan(back.boulders.disc_contact_fx_npm[i]) && isnan(back.boulders.film_fy_npm[i]);
        CHECK(all_nan, "a file without the forces reads them as NaN");
    }
    surge_snapshot_free(&snap);
    surge_snapshot_free(&back);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s OUTPUT_DIR\n", argv[0]);
        return 2;
    }
    test_reserve();
    test_vtp(argv[1]);
    test_pvd(argv[1]);
    test_boulders(argv[1]);
    if (failures != 0) {
        fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    printf("test_vtk_output: all checks passed\n");
    return 0;
}
