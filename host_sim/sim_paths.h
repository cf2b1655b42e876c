/* Where vehicle-sim finds vehicle.xml and io.xml when no --config or --io
 * names them: never the working folder, only places tied to the program.
 *
 *   1. EXE_DIR/../share/vehicle   an installed program (make install puts
 *                                 its configuration there); relative, so a
 *                                 DESTDIR or a moved prefix works too
 *   2. EXE_DIR/<tree>/config      a program in the build folder: the
 *                                 checkout's config/ (<tree> is the way back
 *                                 from BUILD, fixed at build time)
 *   3. DATADIR/vehicle            the installed data folder, fixed at build
 *                                 time (PREFIX/share/vehicle)
 *
 * The first folder that has the file wins.
 */
#ifndef SIM_PATHS_H
#define SIM_PATHS_H

#include <stddef.h>

#define SIM_PATHS_N   3
#define SIM_PATHS_MAX 1024

/* The folders to search, in order, for the program at exe (an absolute
 * path; NULL when unknown: only the fixed data folder). Returns how many. */
size_t sim_paths_dirs(const char *exe, char dirs[SIM_PATHS_N][SIM_PATHS_MAX]);

/* The canonical path of name in the first of dirs that has it, into out.
 * Returns 0, or -1 with out saying where it looked. */
int sim_paths_find(char dirs[][SIM_PATHS_MAX], size_t n, const char *name, char *out, size_t cap);

#endif
