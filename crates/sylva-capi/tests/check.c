/* C code of a host, compiled against include/sylva.h with -Wall -Werror (build.rs) and
 * linked into this crate's tests alone: steps the small scene, builds frames and writes
 * what it reads (palettes, instances, buckets, a wind probe) to the file at `path`, for
 * tests/c_abi.rs to compare bit for bit with the Rust API. */
#include <stdio.h>
#include <string.h>
#include "sylva.h"

int sylva_check(const char *path) {
    if (sylva_abi_version() != SYLVA_ABI_VERSION ||
        sylva_instance_size() != sizeof(SylvaInstance) ||
        sylva_leaf_card_size() != sizeof(SylvaLeafCard)) {
        fprintf(stderr, "ABI mismatch\n");
        return 2;
    }
    if (sylva_forest_new("no such scene") != NULL || sylva_last_error() == NULL) {
        fprintf(stderr, "a bad scene was not refused\n");
        return 3;
    }
    SylvaForest *f = sylva_forest_new("small");
    if (!f) {
        fprintf(stderr, "%s\n", sylva_last_error());
        return 4;
    }
    SylvaCamera camera = sylva_forest_default_camera(f);
    FILE *out = fopen(path, "wb");
    if (!out) {
        return 6;
    }
    for (int k = 0; k < 3; k++) {
        sylva_forest_step(f, 1.0f / 30.0f);
        if (sylva_forest_frame(f, &camera, 4.0f / 3.0f, 768) != 0) {
            fprintf(stderr, "%s\n", sylva_last_error());
            return 5;
        }
    }
    size_t n_pal, n_inst, n_buck;
    const float *pal = sylva_frame_palettes(f, &n_pal);
    const SylvaInstance *inst = sylva_frame_instances(f, &n_inst);
    const SylvaBucket *buck = sylva_frame_buckets(f, &n_buck);
    float p[3] = {0.0f, 0.0f, 10.0f}, wind[3];
    sylva_forest_wind(f, p, wind);
    uint64_t counts[3] = {n_pal, n_inst, n_buck};
    fwrite(counts, sizeof counts, 1, out);
    fwrite(pal, sizeof(float), n_pal, out);
    fwrite(inst, sizeof(SylvaInstance), n_inst, out);
    fwrite(buck, sizeof(SylvaBucket), n_buck, out);
    fwrite(wind, sizeof wind, 1, out);
    /* Every species' every mesh level and both textures, as counts and arrays. */
    uint32_t species = sylva_species_count(f);
    fwrite(&species, sizeof species, 1, out);
    for (uint32_t s = 0; s < species; s++) {
        uint32_t levels = sylva_species_levels(f, s);
        fwrite(&levels, sizeof levels, 1, out);
        for (uint32_t l = 0; l < levels; l++) {
            SylvaMesh m;
            if (sylva_species_mesh(f, s, l, &m) != 0) {
                fprintf(stderr, "%s\n", sylva_last_error());
                return 7;
            }
            uint64_t sizes[3] = {m.vertices, m.indices, m.cards};
            fwrite(sizes, sizeof sizes, 1, out);
            fwrite(m.positions, sizeof(float), 3 * m.vertices, out);
            fwrite(m.normals, sizeof(float), 3 * m.vertices, out);
            fwrite(m.uvs, sizeof(float), 2 * m.vertices, out);
            fwrite(m.joints, sizeof(uint32_t), 4 * m.vertices, out);
            fwrite(m.weights, sizeof(float), 4 * m.vertices, out);
            fwrite(m.index, sizeof(uint32_t), m.indices, out);
            fwrite(m.card, sizeof(SylvaLeafCard), m.cards, out);
        }
        for (uint32_t which = 0; which < 2; which++) {
            uint32_t dims[3];
            const uint8_t *rgba = sylva_species_texture(f, s, which, &dims[0], &dims[1], &dims[2]);
            if (!rgba) {
                fprintf(stderr, "%s\n", sylva_last_error());
                return 8;
            }
            fwrite(dims, sizeof dims, 1, out);
            fwrite(rgba, 4, (size_t)dims[0] * dims[1], out);
        }
    }
    SylvaMesh none;
    if (sylva_species_mesh(f, species, 0, &none) != 2 || sylva_species_texture(f, 0, 2, NULL, NULL, NULL)) {
        fprintf(stderr, "an out-of-range species or texture was not refused\n");
        return 9;
    }
    fclose(out);
    sylva_forest_free(f);
    return 0;
}
