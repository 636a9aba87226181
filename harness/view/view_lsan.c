/* gibench view under AddressSanitizer: Mesa's GLX path loads its DRI
 * driver (swrast_dri.so for llvmpipe) with dlopen and unloads it when the
 * window's context goes, before LeakSanitizer reports at exit; the
 * driver's own allocations then show as "<unknown module>" and the
 * suppressions of tests/lsan.supp, which name Mesa's libraries, cannot
 * match them. In the ASan build only, the loaded DRI drivers are pinned
 * (RTLD_NODELETE), so that the report names them. Nothing in other builds. */
#define _GNU_SOURCE
#include "view.h"

#if defined(__SANITIZE_ADDRESS__)
#include <dlfcn.h>
#include <link.h>
#include <string.h>

static int pin(struct dl_phdr_info *info, size_t size, void *data)
{
    (void)size;
    (void)data;
    const char *name = info->dlpi_name;
    if (name && strstr(name, "_dri.so"))
        dlopen(name, RTLD_NOW | RTLD_NOLOAD |
                         RTLD_NODELETE); /* a reference kept to the end: not closed */
    return 0;
}

void view_pin_gl_driver(void)
{
    dl_iterate_phdr(pin, NULL);
}
#else
void view_pin_gl_driver(void) {}
#endif
