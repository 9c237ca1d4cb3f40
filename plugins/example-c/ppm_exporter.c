/* A Kiln exporter plugin in C: writes the tonemapped film as a binary PPM (P6) image.
 * It shows that kiln_plugin.h is all another language needs. Build it with
 *     cc -shared -fPIC -I plugins/api -o libkiln_ppm.so plugins/example-c/ppm_exporter.c
 * and put the library in a folder given to `kiln --plugin-dir`. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "kiln_plugin.h"

static void fail(KilnErrorBuffer *error, const char *message, const char *path) {
    if (error != NULL && error->data != NULL && error->capacity > 0) {
        snprintf(error->data, error->capacity, "%s: %s", path, message);
    }
}

static unsigned char quantize(float v) {
    if (!(v > 0.0f)) { /* also NaN */
        return 0;
    }
    if (v >= 1.0f) {
        return 255;
    }
    return (unsigned char)floorf(v * 255.0f + 0.5f);
}

static int32_t export_ppm(const char *path, const KilnFilmView *film, const char *options,
                          KilnErrorBuffer *error) {
    (void)options;
    if (film == NULL || film->display == NULL || film->width == 0 || film->height == 0) {
        fail(error, "empty film", path);
        return KILN_STATUS_ERROR;
    }
    /* Written under a temporary name and renamed, so a failure never leaves half a file. */
    char temp[4096];
    if (snprintf(temp, sizeof temp, "%s.part", path) >= (int)sizeof temp) {
        fail(error, "path too long", path);
        return KILN_STATUS_ERROR;
    }
    FILE *f = fopen(temp, "wb");
    if (f == NULL) {
        fail(error, "cannot create the file", path);
        return KILN_STATUS_ERROR;
    }
    fprintf(f, "P6\n%u %u\n255\n", film->width, film->height);
    size_t pixels = (size_t)film->width * film->height;
    for (size_t i = 0; i < pixels; i++) {
        unsigned char rgb[3] = {quantize(film->display[4 * i]), quantize(film->display[4 * i + 1]),
                                quantize(film->display[4 * i + 2])};
        fwrite(rgb, 1, 3, f);
    }
    if (fclose(f) != 0 || rename(temp, path) != 0) {
        remove(temp);
        fail(error, "cannot write the file", path);
        return KILN_STATUS_ERROR;
    }
    return KILN_STATUS_OK;
}

static const KilnPluginDescriptor DESCRIPTOR = {
    KILN_ABI_VERSION, KILN_KIND_EXPORTER, "PPM (C example)", "1.0.0", "ppm", NULL, export_ppm,
};

const KilnPluginDescriptor *kiln_plugin_descriptor(void) {
    return &DESCRIPTOR;
}
