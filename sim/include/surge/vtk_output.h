/* VTK output for ParaView: one XML PolyData file (.vtp) per snapshot, plus a time collection (.pvd)
 * listing them. Every file is written to "<path>.tmp" and then renamed over <path>, so a reader never
 * sees a half-written file. No global state: all functions are safe to use from independent threads
 * on different files. */
#ifndef SURGE_VTK_OUTPUT_H
#define SURGE_VTK_OUTPUT_H

#include <stddef.h>

#include "surge/snapshot.h"

/* Writes snap as a VTK XML PolyData file (version 1.0, LittleEndian, header_type UInt64) with a
 * single raw (binary) <AppendedData> block:
 *   Points      Float64 x3 (x_m, y_m, 0)
 *   Verts       connectivity Int64 0..n-1, offsets Int64 1..n (one vertex cell per particle)
 *   PointData   "velocity_mps" Float32 x3 (vx, vy, 0), "density_kgpm3" Float32,
 *               "pressure_pa" Float32, "kind" UInt8, "id" Int32
 *   FieldData   "time_s" Float64 (1 value), "step" Int64 (1 value)
 * Returns 0 on success. On failure returns -1, removes the temporary file, leaves any existing file
 * at path untouched and puts a message naming the file and strerror(errno) into err (when err is
 * not NULL and err_len > 0). */
int surge_vtp_write(const char *path, const surge_snapshot *snap, char *err, size_t err_len);

/* Writes the boulders of snap (snap->boulders) as a VTK XML PolyData file of one vertex per disc centre:
 *   Points      Float64 x3 (x_m, y_m, 0)
 *   PointData   "velocity_mps" Float64 x3 (vx, vy, 0), "omega_radps", "angle_rad", "radius_m" Float64
 *   FieldData   "time_s" Float64, "step" Int64
 * Same atomic write and error contract as surge_vtp_write. */
int surge_vtp_write_boulders(const char *path, const surge_snapshot *snap, char *err, size_t err_len);

/* Reads a file written by surge_vtp_write into snap (resized as needed). -1 with err naming the file and the
 * problem when it is not such a file. */
int surge_vtp_read(const char *path, surge_snapshot *snap, char *err, size_t err_len);

/* Reads a file written by surge_vtp_write_boulders into snap's boulders (after surge_vtp_read, which empties
 * them). -1 with err naming the file and the problem. */
int surge_vtp_read_boulders(const char *path, surge_snapshot *snap, char *err, size_t err_len);

/* A .pvd time collection (VTKFile type="Collection") being built; opaque. */
typedef struct surge_pvd surge_pvd;

/* Opens the collection at pvd_path and writes it at once (so the file is valid from the start).
 * resume_before_time_s < 0: starts an empty collection (an existing file is replaced).
 * resume_before_time_s >= 0: if pvd_path exists, keeps its <DataSet> entries whose timestep is
 *   < resume_before_time_s (for restarting a run into the same folder); a missing file gives an
 *   empty collection.
 * Returns NULL with a message in err on failure (unreadable or malformed file, cannot write). */
surge_pvd *surge_pvd_open(const char *pvd_path, double resume_before_time_s, char *err, size_t err_len);

/* Appends the entry (time_s, relative_file) and rewrites the whole .pvd (tmp + rename).
 * relative_file is relative to the .pvd's folder; it is XML-escaped on output. Returns 0 on
 * success; on failure returns -1 with a message in err, and the entry is not kept. */
int surge_pvd_add(surge_pvd *pvd, double time_s, const char *relative_file, char *err, size_t err_len);

/* Reads an existing collection without writing it (for rendering a finished run). NULL with err. */
surge_pvd *surge_pvd_read(const char *pvd_path, char *err, size_t err_len);
size_t surge_pvd_count(const surge_pvd *pvd);
const char *surge_pvd_file(const surge_pvd *pvd, size_t index); /* relative to the .pvd's folder */
double surge_pvd_time_s(const surge_pvd *pvd, size_t index);

/* Frees the collection (the file on disk stays as last written). NULL is allowed. */
void surge_pvd_close(surge_pvd *pvd);

#endif
