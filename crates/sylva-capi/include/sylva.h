/* Sylva's C interface onto the live forest simulation (crates/sylva-capi, ABI version 2).
 *
 * Link against the sylva-capi library (libsylva_capi.so, sylva_capi.dll,
 * libsylva_capi.dylib). Conventions: Z-up, metres, seconds, m/s. A function that fails
 * returns NULL or a non-zero status and leaves a message for sylva_last_error() on the
 * calling thread. The frame arrays stay valid until the next sylva_forest_frame() or
 * sylva_forest_free() on that forest; the meshes and textures until sylva_forest_free(). A change to any signature or layout here raises
 * SYLVA_ABI_VERSION. */
#ifndef SYLVA_H
#define SYLVA_H

#include <stddef.h>
#include <stdint.h>

#define SYLVA_ABI_VERSION 2

typedef struct SylvaForest SylvaForest;

/* Eye and target (world m), vertical field of view (degrees), clip distances (m). */
typedef struct SylvaCamera {
    float eye[3];
    float target[3];
    float fov_deg;
    float near;
    float far;
} SylvaCamera;

/* One drawn tree. Its joint palettes: element e (0..12) of joint j at
 * palettes[palette_base + (12 * j + e) * palette_stride], a 3x4 row-major matrix taking the
 * tree's rest pose to its animated pose, in tree space (before yaw, scale and position). */
typedef struct SylvaInstance {
    float position[3];      /* trunk base, world m */
    float yaw;              /* rotation about z, rad */
    float scale;            /* uniform scale */
    uint32_t palette_base;
    uint32_t palette_stride;
    float leaf_phase;       /* leaf flutter phase, rad */
    float leaf_amplitude;   /* leaf flutter amplitude, rad */
    float fade[2];          /* keep pixels whose dither value d in [0, 1) is in [fade[0], fade[1]) */
    uint32_t tag;           /* bits 0-3 level (15 impostor), 4-7 species, 8-31 instance group */
    uint16_t lean[2];       /* an impostor's crown lean, half floats, m */
    uint16_t tilt[2];       /* an impostor's leaf tilt, half floats */
} SylvaInstance;

/* One instanced draw: count instances from first, of one species at one level (level equal
 * to the species' number of mesh levels: its impostor); shadow_only draws go to the shadow
 * map alone, cast at mesh level shadow_level. */
typedef struct SylvaBucket {
    uint32_t species;
    uint32_t level;
    uint32_t shadow_level;
    uint32_t first;
    uint32_t count;
    uint32_t shadow_only;
} SylvaBucket;

/* One leaf card of a mesh level, tree space: a square of side `size` about `center`, facing
 * `normal`, its "up" the direction from `hang` (where it hangs on joint `joint`) to its
 * centre projected onto it, turned by `roll`; it shows cell `atlas` of the species' leaf
 * atlas, `leaf_area` m2 of leaves; `exposure` 1 at the crown's surface, 0 at its centre
 * (darken inner foliage); `phase` its flutter phase. A renderer may turn cards part way
 * towards the viewer, as Sylva's does. */
typedef struct SylvaLeafCard {
    uint32_t joint;
    float hang[3];
    float center[3];
    float size;
    float roll;
    uint32_t atlas;
    float phase;
    float leaf_area;
    float normal[3];
    float exposure;
} SylvaLeafCard;

/* One mesh level of a species, tree space (before an instance's yaw, scale, position), in
 * place: branch vertices (positions and normals 3 floats each, bark uvs 2, joint indices
 * and weights 4 each: the joint indices are the forest's, so an instance's palettes skin
 * the mesh as they are), triangle corners (counter-clockwise from outside), leaf cards. */
typedef struct SylvaMesh {
    size_t vertices;
    const float *positions;
    const float *normals;
    const float *uvs;
    const uint32_t *joints;
    const float *weights;
    size_t indices;
    const uint32_t *index;
    size_t cards;
    const SylvaLeafCard *card;
} SylvaMesh;

uint32_t sylva_abi_version(void);
size_t sylva_instance_size(void);
size_t sylva_leaf_card_size(void);
const char *sylva_last_error(void);

/* A built-in scene (small, A, B, C, D) or a scene file's path (UTF-8); NULL on error. */
SylvaForest *sylva_forest_new(const char *scene);
void sylva_forest_free(SylvaForest *forest);
/* Advance by dt seconds of simulated time. 0, or 1 for NULL. */
int32_t sylva_forest_step(SylvaForest *forest, float dt);
SylvaCamera sylva_forest_default_camera(SylvaForest *forest);
/* Build the frame for camera and an image of aspect = width / height, rows pixels tall.
 * 0; 1 for NULL; 2 for a camera that is not finite. */
int32_t sylva_forest_frame(SylvaForest *forest, const SylvaCamera *camera, float aspect, uint32_t rows);
const float *sylva_frame_palettes(SylvaForest *forest, size_t *count);
const SylvaInstance *sylva_frame_instances(SylvaForest *forest, size_t *count);
const SylvaBucket *sylva_frame_buckets(SylvaForest *forest, size_t *count);
/* The wind at world point p[3] (m) now, in m/s, into out[3]. 0, or 1 for NULL. */
int32_t sylva_forest_wind(SylvaForest *forest, const float *p, float *out);

/* The scene's species, and the mesh levels of one (a bucket of level equal to it draws the
 * species' impostor); 0 for NULL or out of range. */
uint32_t sylva_species_count(SylvaForest *forest);
uint32_t sylva_species_levels(SylvaForest *forest, uint32_t species);
/* Mesh `level` of `species` into *out. 0; 1 for NULL; 2 for a species or level out of range. */
int32_t sylva_species_mesh(SylvaForest *forest, uint32_t species, uint32_t level, SylvaMesh *out);
/* A species' texture, RGBA8 sRGB, rows top first: which 0 the bark (tiling), 1 the leaf
 * atlas (*cells x *cells cells, a card showing cell `atlas`; alpha the leaves' outline).
 * Sets *width, *height, *cells (1 for the bark); NULL on error. */
const uint8_t *sylva_species_texture(SylvaForest *forest, uint32_t species, uint32_t which,
                                     uint32_t *width, uint32_t *height, uint32_t *cells);

#endif
