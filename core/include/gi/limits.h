/* Every size limit gibench enforces on its input, in one place (README.md
 * "Limits and failures", docs/core.md "Limits").
 *
 * Use: include it (gi/scene.h and gi/image.h do) and test a declared size
 * against the limit before anything is allocated or decoded; the message
 * states the limit ("... exceed the limit of 16777216 triangles"). Each
 * limit is chosen so that input at the limit runs in a few GiB of memory;
 * input beyond it is refused with a one-line error in well under a second,
 * where it would otherwise cost tens of seconds and many GiB before
 * failing (issue 32 item 10).
 */
#ifndef GI_LIMITS_H
#define GI_LIMITS_H

/* GI_MAX_OBJECTS (256): objects (nodes with a mesh) in a scene; the
 * object-transform UBO holds this many, so the GLSL side shares it. */
#include "gi/glsl_shared.h"

/* Scene files (glTF, .bin buffers, images, environment maps) on disk. */
#define GI_MAX_FILE_BYTES (1024ull * 1024ull * 1024ull)
/* Triangles and vertices of a scene in all (and of each mesh). */
#define GI_MAX_TRIANGLES (16u * 1024u * 1024u)
#define GI_MAX_VERTICES (48u * 1024u * 1024u)
#define GI_MAX_MATERIALS 4096

/* A texture image's width and height, each (read from the PNG or JPEG
 * header before it is decoded). */
#define GI_MAX_TEXTURE_SIZE 8192
/* Texels a scene's textures hold in all: the decoded images together, and
 * the float RGBA textures made from them together (16 bytes a texel: 1 GiB).
 * One image listed as many textures counts once per texture. */
#define GI_MAX_TEXTURE_TEXELS (64u * 1024u * 1024u)

/* The size of a rendered image (render, reference, view, study "size",
 * saved views): each side at most GI_MAX_IMAGE_SIDE, and at most
 * GI_MAX_IMAGE_PIXELS pixels (4096 x 4096) in all. */
#define GI_MAX_IMAGE_SIDE 8192u
#define GI_MAX_IMAGE_PIXELS (4096u * 4096u)
/* The rule as the messages state it. */
#define GI_IMAGE_SIZE_RULE "1..8192 each and at most 16777216 pixels (4096x4096)"
/* Does a rendered image of w x h pixels keep the rule? */
static inline int gi_image_size_ok(unsigned long long w, unsigned long long h)
{
    return w >= 1 && h >= 1 && w <= GI_MAX_IMAGE_SIDE && h <= GI_MAX_IMAGE_SIDE &&
           w * h <= GI_MAX_IMAGE_PIXELS;
}

/* Image files read (EXR, PNG, PFM, ...: references, environment maps,
 * diff inputs): at most GI_MAX_IMAGE_FILE_PIXELS pixels (an 8192 x 4096
 * environment map), and at most GI_MAX_IMAGE_FILE_VALUES values (pixels x
 * channels, 1 GiB as floats) and GI_MAX_IMAGE_FILE_CHANNELS channels; the
 * header's data and display windows are checked before any pixel is read. */
#define GI_MAX_IMAGE_FILE_PIXELS (8192ull * 4096ull)
#define GI_MAX_IMAGE_FILE_VALUES (256ull * 1024ull * 1024ull)
#define GI_MAX_IMAGE_FILE_CHANNELS 1024

/* JSON files users write (studies, saved views): read whole, so bounded. */
#define GI_MAX_JSON_BYTES (16ull * 1024ull * 1024ull)

/* gi_image_create: the largest image allocated at all (4 floats a pixel:
 * 4 GiB); anything bigger is a bug, not a render. */
#define GI_MAX_IMAGE_ALLOC_PIXELS (1ull << 28)

#endif
