/* A narrow C interface to Embree 3 or 4 for ember.
 *
 * No Embree type appears here: Embree's own `rtcInit*` helpers are inline functions
 * with no library symbol, so bindings generated from rtcore.h would differ between
 * versions and name functions that do not exist. Bindings of this header are the same
 * for Embree 3 and 4; shim.c holds the lines that differ.
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

/* Rays per packet of the 16-lane functions. */
#define EMBER_LANES 16

typedef struct ember_ray {
  float org[3];
  float tnear;
  float dir[3];
  float tfar;
  /* The primitive the ray was spawned from (ember id), or EMBER_NO_PRIM. A ray never
   * hits that triangle; it hits that sphere only at its far side, when its origin lies
   * inside (the spawn offset moved it to the side the ray heads to), as the native
   * BVH does. How the scene enforces it: EMBER_SELF_*. */
  uint32_t skip;
} ember_ray;

typedef struct ember_hit {
  float t;
  /* Unnormalized geometric normal, as Embree reports it (zero for user spheres). */
  float ng[3];
  /* Barycentric weights of corners 1 and 2 (triangles only). */
  float u;
  float v;
  /* ember primitive id: triangles first, then spheres; EMBER_NO_PRIM on a miss. */
  uint32_t prim;
} ember_hit;

/* Sixteen rays with tnear 0, structure of arrays (ember's RayPacket): lane i is
 * org[k * 16 + i] + t * dir[k * 16 + i], t in [0, tfar[i]], skipping skip[i]. */
typedef struct ember_packet {
  const float *org;
  const float *dir;
  const float *tfar;
  const uint32_t *skip;
} ember_packet;

/* Where the 16-lane functions write hits (ember's HitPacket): only active lanes are
 * written; a miss is t = +inf, prim = EMBER_NO_PRIM, u = v = 0. */
typedef struct ember_packet_hits {
  float *t;
  uint32_t *prim;
  float *u;
  float *v;
} ember_packet_hits;

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

/* How the 16-lane functions hand rays to Embree. */
/* Each ray alone: rtcIntersect1 / rtcOccluded1. */
#define EMBER_QUERIES_SINGLE 0
/* The active lanes as one rtcIntersect16 / rtcOccluded16 packet. */
#define EMBER_QUERIES_PACKET16 1
/* Embree 3: the active lanes as one rtcIntersect1M / rtcOccluded1M stream (Embree 4
 * has no streams: single rays). */
#define EMBER_QUERIES_STREAM 2
/* Single rays, except that intersection lanes without a skip (camera rays) go in
 * rtcIntersect8 packets with the coherent flag, one per half of the lanes. */
#define EMBER_QUERIES_CAMERA8 3
/* Each half of the lanes as an rtcIntersect8 / rtcOccluded8 packet (incoherent, or
 * with Embree's coherent flag). */
#define EMBER_QUERIES_PACKET8 4
#define EMBER_QUERIES_PACKET8_COHERENT 5

/* How a ray spawned from a surface (skip set) avoids the primitive it leaves. */
/* The skip filter on every candidate hit of such a ray. */
#define EMBER_SELF_FILTER 0
/* Intersection without the filter, traced again with it when the nearest hit is the
 * primitive skipped (the result is the filter's, exactly); occlusion with the filter. */
#define EMBER_SELF_RETRY 1
/* No filter: only the origin offset by the hit point's error bound. */
#define EMBER_SELF_OFFSET 2

/* A ray-sphere test: the nearest t in [tnear, tfar] where the ray meets the sphere
 * (x, y, z, r), or a negative number on a miss; `leaving`: the ray was spawned from
 * this sphere's surface (so only its far side counts). */
typedef float (*ember_sphere_fn)(const float org[3], const float dir[3], float tnear,
                                 float tfar, const float sphere[4], int leaving);

typedef struct ember_scene_options {
  int quality;
  /* RTC_SCENE_FLAG_ROBUST. */
  int robust;
  int queries;
  int self_hits;
  /* NULL: spheres as Embree's RTC_GEOMETRY_TYPE_SPHERE_POINT; else user geometry
   * whose hits this function decides (and with them the sphere's own skip). */
  ember_sphere_fn sphere;
} ember_scene_options;

/* Builds and commits a scene of `ntri` triangles (indices into `vertices`, xyz floats)
 * and `nsph` spheres (x, y, z, r floats). The arrays are copied. Triangles get
 * primitive ids 0..ntri, spheres ntri..ntri+nsph. Returns NULL on failure; the
 * reason is then available from ember_device_take_error. */
ember_scene *ember_scene_new(ember_device *device, const float *vertices, size_t nvert,
                             const uint32_t *indices, size_t ntri, const float *spheres,
                             size_t nsph, const ember_scene_options *options);

/* The scene flags a scene was built with, as RTC_SCENE_FLAG_* bits. */
#define EMBER_SCENE_FLAG_ROBUST 4
int ember_scene_flags(const ember_scene *scene);

void ember_scene_release(ember_scene *scene);

/* Nearest hit in [tnear, tfar]. Returns 1 and fills `hit` on a hit, else 0. */
int ember_intersect1(const ember_scene *scene, const ember_ray *ray, ember_hit *hit);

/* Returns 1 when anything lies on the ray in [tnear, tfar]. */
int ember_occluded1(const ember_scene *scene, const ember_ray *ray);

/* Nearest hits of `n` rays without skips (1 <= n <= width) traced as one Embree packet
 * of `width` lanes (4, 8 or 16: rtcIntersect4/8/16, coherent); lanes past `n` are
 * masked off. Fills hits[0..n] (prim EMBER_NO_PRIM on a miss) and returns the number
 * of hits, or -1 for a bad width or n. */
int ember_intersect_packet(const ember_scene *scene, int width, const ember_ray *rays,
                           size_t n, ember_hit *hits);

/* Nearest hits of the lanes of `active` (bit i: lane i), each ray skipping its own
 * primitive, traced as the scene's `queries` say. */
void ember_intersect16(const ember_scene *scene, const ember_packet *rays, uint32_t active,
                       const ember_packet_hits *hits);

/* The active lanes that are occluded, traced as the scene's `queries` say. */
uint32_t ember_occluded16(const ember_scene *scene, const ember_packet *rays, uint32_t active);

#ifdef __cplusplus
}
#endif

#endif
