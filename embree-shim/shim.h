/* A narrow C interface to Embree 3 or 4 for ember.
 *
 * No Embree type appears here: Embree's own `rtcInit*` helpers are inline functions
 * with no library symbol, so bindings generated from rtcore.h would differ between
 * versions and name functions that do not exist. Bindings of this header are the same
 * for Embree 3 and 4; shim.c holds the ~20 lines that differ.
 */
#ifndef EMBER_EMBREE_SHIM_H
#define EMBER_EMBREE_SHIM_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct ember_device ember_device;
typedef struct ember_scene ember_scene;

/* Build quality, as RTC_BUILD_QUALITY_{LOW,MEDIUM,HIGH}. */
#define EMBER_QUALITY_LOW 0
#define EMBER_QUALITY_MEDIUM 1
#define EMBER_QUALITY_HIGH 2

/* Returned as `prim` when nothing was hit. */
#define EMBER_NO_PRIM 0xFFFFFFFFu

typedef struct ember_ray {
  float org[3];
  float tnear;
  float dir[3];
  float tfar;
  /* The primitive the ray was spawned from (ember id), or EMBER_NO_PRIM. A ray never
   * hits that triangle; it hits that sphere only at its far side, when its origin lies
   * inside (the spawn offset moved it to the side the ray heads to), as the native
   * BVH does. Applied by a filter function (single rays; packets take no skip). */
  uint32_t skip;
} ember_ray;

typedef struct ember_hit {
  float t;
  /* Unnormalized geometric normal, as Embree reports it. */
  float ng[3];
  /* Barycentric weights of corners 1 and 2 (triangles only). */
  float u;
  float v;
  /* ember primitive id: triangles first, then spheres; EMBER_NO_PRIM on a miss. */
  uint32_t prim;
} ember_hit;

typedef struct ember_device_info {
  int version_major;
  int version_minor;
  int version_patch;
  /* Widest native ray packet (1, 4, 8 or 16): 4 means SSE, 8 AVX/AVX2, 16 AVX-512 kernels. */
  int native_packet_width;
  int backface_culling;
  int ray_mask_supported;
} ember_device_info;

/* Creates a device with an Embree config string (e.g. "threads=2,start_threads=1").
 * Returns NULL on failure and writes the reason into `err` (NUL-terminated). */
ember_device *ember_device_new(const char *config, char *err, size_t err_len);

/* Releases the device; scenes built on it must already be released. */
void ember_device_release(ember_device *device);

/* Copies the last error reported by Embree's error callback into `buf` and clears it.
 * Returns the message length (0 when no error was recorded). Thread-safe. */
size_t ember_device_take_error(ember_device *device, char *buf, size_t len);

/* Bytes currently allocated by this device, as reported to its memory monitor. */
int64_t ember_device_memory_bytes(const ember_device *device);

void ember_device_get_info(const ember_device *device, ember_device_info *info);

/* Builds and commits a scene of `ntri` triangles (indices into `vertices`, xyz floats)
 * and `nsph` spheres (x, y, z, r floats). The arrays are copied. Triangles get
 * primitive ids 0..ntri, spheres ntri..ntri+nsph. Returns NULL on failure; the
 * reason is then available from ember_device_take_error. */
ember_scene *ember_scene_new(ember_device *device, const float *vertices, size_t nvert,
                             const uint32_t *indices, size_t ntri, const float *spheres,
                             size_t nsph, int quality, int robust);

/* The scene flags a scene was built with, as RTC_SCENE_FLAG_* bits (0: none,
 * EMBER_SCENE_FLAG_ROBUST: robust traversal). */
#define EMBER_SCENE_FLAG_ROBUST 4
int ember_scene_flags(const ember_scene *scene);

void ember_scene_release(ember_scene *scene);

/* Nearest hit in [tnear, tfar]. Returns 1 and fills `hit` on a hit, else 0. */
int ember_intersect1(const ember_scene *scene, const ember_ray *ray, ember_hit *hit);

/* Returns 1 when anything lies on the ray in [tnear, tfar]. */
int ember_occluded1(const ember_scene *scene, const ember_ray *ray);

/* Nearest hits of `n` rays (1 <= n <= width) traced as one Embree packet of `width`
 * lanes (4, 8 or 16: rtcIntersect4/8/16); lanes past `n` are masked off. Fills
 * hits[0..n] (prim EMBER_NO_PRIM on a miss) and returns the number of hits, or -1 for
 * a bad width or n. */
int ember_intersect_packet(const ember_scene *scene, int width, const ember_ray *rays,
                           size_t n, ember_hit *hits);

/* Nearest hits of the lanes of `active` (bit i: rays[i], rays holds 16) traced as one
 * rtcIntersect16 packet, each ray skipping its own primitive as ember_intersect1 does;
 * fills hits[i] of the active lanes. */
void ember_intersect16(const ember_scene *scene, const ember_ray *rays, uint32_t active,
                       ember_hit *hits);

/* The active lanes (bit i: rays[i], rays holds 16) that are occluded, traced as one
 * rtcOccluded16 packet with each ray's skip applied. */
uint32_t ember_occluded16(const ember_scene *scene, const ember_ray *rays, uint32_t active);

#ifdef __cplusplus
}
#endif

#endif
