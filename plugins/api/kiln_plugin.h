/* Kiln plugin ABI, version 2: the C declarations of plugins/api/src/lib.rs.
 *
 * A plugin is a shared library exporting
 *     const KilnPluginDescriptor *kiln_plugin_descriptor(void);
 * whose result's first field is KILN_ABI_VERSION. The host reads nothing else from a
 * descriptor of another version. Strings are NUL-terminated UTF-8 and must stay valid
 * while the library is loaded. docs/PLUGINS.md has complete examples. */
#ifndef KILN_PLUGIN_H
#define KILN_PLUGIN_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

#define KILN_ABI_VERSION 2u
#define KILN_KIND_IMPORTER 1u
#define KILN_KIND_EXPORTER 2u
#define KILN_KIND_MATERIAL 3u /* a material format (version 2 on) */
#define KILN_STATUS_OK 0
#define KILN_STATUS_ERROR 1
#define KILN_INVALID_ID 0xffffffffu

#define KILN_LIGHT_POINT 0u
#define KILN_LIGHT_SPOT 1u
#define KILN_LIGHT_DISTANT 2u

typedef struct KilnErrorBuffer {
    char *data;
    size_t capacity;
} KilnErrorBuffer;

typedef struct KilnMeshData {
    const char *name;
    size_t vertex_count;
    const float *positions; /* 3 per vertex */
    const float *normals;   /* 3 per vertex, or NULL */
    const float *uvs;       /* 2 per vertex, or NULL */
    const float *uvs1;      /* a second UV set (TEXCOORD_1), 2 per vertex, or NULL */
    const float *tangents;  /* 4 per vertex, or NULL */
    const float *colors;    /* 4 per vertex, or NULL */
    const uint32_t *indices; /* 3 per triangle */
    size_t index_count;
} KilnMeshData;

typedef struct KilnCameraData {
    float to_world[16]; /* column-major; the camera looks down its -z, y up */
    float fov_y_degrees;
    float aperture_radius;
    float focus_distance;
} KilnCameraData;

typedef struct KilnLightData {
    uint32_t kind;
    float position[3];
    float direction[3];
    float intensity[3];
    float cone_angle_degrees; /* half-angle of a spot's cone */
    float blend;              /* fraction of the cone over which it fades out */
    float radius;
} KilnLightData;

typedef struct KilnSceneBuilder {
    void *ctx;
    uint32_t (*add_mesh)(void *ctx, const KilnMeshData *mesh);
    uint32_t (*add_material)(void *ctx, const char *name, const char *kmat);
    uint32_t (*add_image)(void *ctx, const char *name, const uint8_t *bytes, size_t len);
    uint32_t (*add_instance)(void *ctx, uint32_t mesh, uint32_t material, const float (*to_world)[16]);
    void (*set_camera)(void *ctx, const KilnCameraData *camera);
    uint32_t (*add_light)(void *ctx, const KilnLightData *light);
    void (*warn)(void *ctx, const char *message);
} KilnSceneBuilder;

typedef struct KilnLayerView {
    const char *name;
    uint32_t channels;
    const float *data;
} KilnLayerView;

typedef struct KilnFilmView {
    uint32_t width;
    uint32_t height;
    const float *radiance; /* linear RGBA */
    const float *display;  /* tonemapped, sRGB-encoded RGBA in [0, 1] */
    uint32_t layer_count;
    const KilnLayerView *layers;
} KilnFilmView;

typedef int32_t (*KilnImportFn)(const char *path, const KilnSceneBuilder *builder, KilnErrorBuffer *error);
typedef int32_t (*KilnExportFn)(const char *path, const KilnFilmView *film, const char *options,
                                KilnErrorBuffer *error);

/* Material formats (version 2 on). Materials are the text of .kmat files
 * (docs/NODES.md); files they name are relative to the material file. */
typedef struct KilnMaterialSink {
    void *ctx;
    uint32_t (*add_material)(void *ctx, const char *name, const char *kmat);
    void (*warn)(void *ctx, const char *message);
} KilnMaterialSink;

typedef int32_t (*KilnMaterialImportFn)(const char *path, const KilnMaterialSink *sink,
                                        KilnErrorBuffer *error);
/* library: the node types kmat uses, their sockets typed (RON, docs/PLUGINS.md). */
typedef int32_t (*KilnMaterialExportFn)(const char *path, const char *name, const char *kmat,
                                        const char *library, KilnErrorBuffer *error);

typedef struct KilnPluginDescriptor {
    uint32_t abi_version; /* must be first */
    uint32_t kind;
    const char *name;
    const char *version;
    const char *extensions; /* "gltf,glb" */
    KilnImportFn import;    /* importers */
    KilnExportFn export_;   /* exporters */
    /* Version 2 on; a version-1 descriptor ends above (an initialiser that leaves them
     * out sets them to NULL). */
    KilnMaterialImportFn import_material; /* material formats that read */
    KilnMaterialExportFn export_material; /* material formats that write */
} KilnPluginDescriptor;

#ifdef __cplusplus
}
#endif

#endif
