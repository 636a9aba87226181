/* Optional modules: shared objects that bring heavy libraries (OpenImageIO,
 * VTK) into a process only when a command needs them, so that every other
 * command starts without them (the dynamic linker's work grows with the
 * number of libraries linked, and every study cell is a new process).
 *
 * A module is a file in the directory that holds libgicore.so (the build's
 * lib/ folder, or wherever the two are installed together). It is opened
 * once, on first use, with dlopen(RTLD_NOW | RTLD_LOCAL) and never closed.
 * A module that is missing or cannot be loaded is an error with one line:
 * "<what> needs the module <path>: <dlerror text>".
 *
 * Modules of the tree: gi_image_oiio.so (image formats beyond EXR, PFM and
 * PNG writing and EXR reading; core/modules/image_oiio.cpp) and
 * libgi_charts.so (the report charts; harness/report/charts.cpp).
 */
#ifndef GI_MODULE_H
#define GI_MODULE_H

#include "gi/common.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The address of `symbol` in module `file` (e.g. "gi_image_oiio.so"),
 * opening the module on first use; thread-safe. NULL on failure with
 * "<what> needs the module <path>: <reason>" in err (GI_ERR_UNSUPPORTED). */
void *gi_module_symbol(const char *file, const char *symbol, const char *what, gi_error *err);

/* The directory the modules are looked up in (that of libgicore.so),
 * without a trailing slash; "" if it cannot be found. */
const char *gi_module_dir(void);

#ifdef __cplusplus
}
#endif
#endif
