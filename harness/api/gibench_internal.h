/* What the files of libgibench share (not part of gi/gibench.h). */
#ifndef GIBENCH_API_INTERNAL_H
#define GIBENCH_API_INTERNAL_H

#include "gi/gibench.h"
#include "gi/scene.h"

#include <json-c/json.h>

/* The loaded scene of a gibench_scene. */
const gi_scene *gibench_scene_of(const gibench_scene *s);
/* The JSON text of j (released) into *out, for gibench_free. */
gi_result gibench_json_out(json_object *j, char **out, gi_error *err);

#endif
