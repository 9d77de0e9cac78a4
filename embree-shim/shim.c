/* Embree 3 / 4 implementation of shim.h. build.rs defines EMBER_EMBREE_MAJOR (3 or 4)
 * to pick the header; the API differences are switched on RTC_VERSION_MAJOR. */
#include "shim.h"

#if defined(EMBER_EMBREE_MAJOR) && EMBER_EMBREE_MAJOR >= 4
#include <embree4/rtcore.h>
#else
#include <embree3/rtcore.h>
#endif

#include <float.h>
#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Bytes of room after every ray-hit record handed to Embree. Embree 4.3 and newer,
 * built with instance arrays (its default, and the embreex4 wheel's 4.4), append
 * instPrimID[levels][lanes] to the hit and write it on every hit; embree4-sys ships
 * 4.2's headers, whose records end before it. Every field the shim reads or writes
 * keeps its offset, so trailing room is all the difference needs. */
#define EMBER_HIT_SLACK 256

#define EMBER_TRI_GEOM_ID 0u
#define EMBER_SPH_GEOM_ID 1u

/* Embree checks (in debug builds) and its AVX-512 packet kernels assume this. */
#define EMBER_ALIGN __attribute__((aligned(64)))

struct ember_device {
  RTCDevice device;
  /* Guards last_error: the error callback may fire on Embree's worker threads. */
  atomic_flag lock;
  char last_error[512];
  size_t last_error_len;
  /* Net bytes allocated, from the memory monitor (also called on worker threads). */
  _Atomic int64_t memory;
};

struct ember_scene {
  RTCScene scene;
  uint32_t ntri;
  int flags;
  int queries;
  int self_hits;
  /* The spheres (x, y, z, r), in Embree's sphere buffer or, for user spheres, our own. */
  const float *spheres;
  /* User spheres: ember's test, and the copy it reads (freed with the scene). */
  ember_sphere_fn sphere_fn;
  float *user_spheres;
};

#if RTC_VERSION_MAJOR >= 4
typedef struct RTCRayQueryContext ember_rtc_context;
#define EMBER_SCENE_FLAG_FILTER RTC_SCENE_FLAG_FILTER_FUNCTION_IN_ARGUMENTS
#else
typedef struct RTCIntersectContext ember_rtc_context;
#define EMBER_SCENE_FLAG_FILTER RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION
#endif

/* Embree's context, extended with what the skip filter and the user spheres need:
 * Embree hands both the context pointer it was given, so they reach the fields after it. */
typedef struct skip_context {
  ember_rtc_context ctx;
  const ember_scene *scene;
  uint32_t skip;
  /* Packets and streams: the primitive each ray skips, by ray id (NULL for single rays). */
  const uint32_t *skips;
} skip_context;

/* A fresh Embree context: the primitive a single ray skips, or per ray id the
 * primitives the rays of a packet or stream skip. */
static void init_skip_context(skip_context *sc, const ember_scene *s, uint32_t skip,
                              const uint32_t *skips) {
#if RTC_VERSION_MAJOR >= 4
  rtcInitRayQueryContext(&sc->ctx);
#else
  rtcInitIntersectContext(&sc->ctx);
#endif
  sc->scene = s;
  sc->skip = skip;
  sc->skips = skips;
}

/* Field k of lane i of Embree's ray, hit or ray-hit records of runtime size n
 * (rtcore_ray.h's RTCRayN_* and RTCHitN_* helpers exist only for C++): rays hold
 * org xyz, tnear, dir xyz, time, tfar, mask, id, flags; hits Ng xyz, u, v, primID,
 * geomID, instID; a ray-hit record is a ray then a hit, each field n lanes. */
#define EMBER_F(rec, k, n, i) (((float *)(rec))[(k) * (n) + (i)])
#define EMBER_U(rec, k, n, i) (((unsigned *)(rec))[(k) * (n) + (i)])
#define EMBER_RAY_TFAR 8
#define EMBER_RAY_ID 10
#define EMBER_HIT 12

static uint32_t skip_of(const void *ctx, const void *ray, unsigned n, unsigned i) {
  const skip_context *sc = (const skip_context *)ctx;
  return sc->skips ? sc->skips[EMBER_U(ray, EMBER_RAY_ID, n, i)] : sc->skip;
}

static void lock_device(ember_device *d) {
  while (atomic_flag_test_and_set_explicit(&d->lock, memory_order_acquire)) {
  }
}

static void unlock_device(ember_device *d) {
  atomic_flag_clear_explicit(&d->lock, memory_order_release);
}

static const char *error_name(enum RTCError code) {
  switch (code) {
  case RTC_ERROR_NONE: return "none";
  case RTC_ERROR_UNKNOWN: return "unknown error";
  case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
  case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
  case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
  case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
  case RTC_ERROR_CANCELLED: return "cancelled";
  default: return "error";
  }
}

static void on_error(void *user, enum RTCError code, const char *str) {
  ember_device *d = (ember_device *)user;
  lock_device(d);
  int n = snprintf(d->last_error, sizeof d->last_error, "%s: %s", error_name(code),
                   str ? str : "");
  d->last_error_len = n < 0 ? 0 : ((size_t)n < sizeof d->last_error ? (size_t)n : sizeof d->last_error - 1);
  unlock_device(d);
}

static bool on_memory(void *user, ssize_t bytes, bool post) {
  (void)post;
  ember_device *d = (ember_device *)user;
  atomic_fetch_add_explicit(&d->memory, (int64_t)bytes, memory_order_relaxed);
  return true;
}

static void copy_message(char *dst, size_t len, const char *src) {
  if (dst && len > 0) {
    strncpy(dst, src, len - 1);
    dst[len - 1] = '\0';
  }
}

ember_device *ember_device_new(const char *config, char *err, size_t err_len) {
  ember_device *d = (ember_device *)calloc(1, sizeof *d);
  if (!d) {
    copy_message(err, err_len, "out of memory");
    return NULL;
  }
  atomic_flag_clear(&d->lock);
  atomic_init(&d->memory, 0);
  d->device = rtcNewDevice(config);
  if (!d->device) {
    enum RTCError code = rtcGetDeviceError(NULL);
    char msg[256];
    snprintf(msg, sizeof msg, "rtcNewDevice(\"%s\") failed: %s", config ? config : "",
             error_name(code));
    copy_message(err, err_len, msg);
    free(d);
    return NULL;
  }
  rtcSetDeviceErrorFunction(d->device, on_error, d);
  rtcSetDeviceMemoryMonitorFunction(d->device, on_memory, d);
  return d;
}

void ember_device_release(ember_device *d) {
  if (!d) return;
  rtcReleaseDevice(d->device);
  free(d);
}

size_t ember_device_take_error(ember_device *d, char *buf, size_t len) {
  lock_device(d);
  size_t n = d->last_error_len;
  if (n > 0) copy_message(buf, len, d->last_error);
  d->last_error_len = 0;
  d->last_error[0] = '\0';
  unlock_device(d);
  return n;
}

int64_t ember_device_memory_bytes(const ember_device *d) {
  return atomic_load_explicit(&((ember_device *)d)->memory, memory_order_relaxed);
}

void ember_device_get_info(const ember_device *d, ember_device_info *info) {
  RTCDevice dev = d->device;
  info->version_major = (int)rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION_MAJOR);
  info->version_minor = (int)rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION_MINOR);
  info->version_patch = (int)rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION_PATCH);
  int width = 1;
  if (rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED)) width = 4;
  if (rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED)) width = 8;
  if (rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED)) width = 16;
  info->native_packet_width = width;
  info->backface_culling =
      (int)rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_BACKFACE_CULLING_ENABLED);
  info->ray_mask_supported =
      (int)rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_RAY_MASK_SUPPORTED);
}

/* Embree 4 runs a query's own filter (RTCIntersectArguments.filter) only on geometries
 * that opt in; Embree 3 runs the context's filter on every geometry. */
static void enable_query_filter(RTCGeometry g) {
#if RTC_VERSION_MAJOR >= 4
  rtcSetGeometryEnableFilterFunctionFromArguments(g, true);
#else
  (void)g;
#endif
}

/* Copies into buffers Embree allocates, which it pads as its SIMD loads need. */
static int attach_triangles(RTCDevice dev, RTCScene scene, const float *vertices,
                            size_t nvert, const uint32_t *indices, size_t ntri) {
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
  if (!g) return 0;
  float *vb = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                               3 * sizeof(float), nvert);
  uint32_t *ib = (uint32_t *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0,
                                                     RTC_FORMAT_UINT3, 3 * sizeof(uint32_t), ntri);
  if (!vb || !ib) {
    rtcReleaseGeometry(g);
    return 0;
  }
  memcpy(vb, vertices, nvert * 3 * sizeof(float));
  memcpy(ib, indices, ntri * 3 * sizeof(uint32_t));
  enable_query_filter(g);
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(scene, g, EMBER_TRI_GEOM_ID);
  rtcReleaseGeometry(g);
  return 1;
}

static int attach_spheres(RTCDevice dev, RTCScene scene, ember_scene *s, const float *spheres,
                          size_t nsph) {
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
  if (!g) return 0;
  float *vb = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                               4 * sizeof(float), nsph);
  if (!vb) {
    rtcReleaseGeometry(g);
    return 0;
  }
  memcpy(vb, spheres, nsph * 4 * sizeof(float));
  s->spheres = vb;
  enable_query_filter(g);
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(scene, g, EMBER_SPH_GEOM_ID);
  rtcReleaseGeometry(g);
  return 1;
}

/* ---- spheres as user geometry: ember's own test decides each hit ---- */

static void user_sphere_bounds(const struct RTCBoundsFunctionArguments *args) {
  const ember_scene *s = (const ember_scene *)args->geometryUserPtr;
  const float *c = s->spheres + 4 * (size_t)args->primID;
  /* A few ulps of room: the test's roots may round just outside the exact sphere. */
  float pad = fmaxf(fmaxf(fabsf(c[0]), fabsf(c[1])), fabsf(c[2]));
  pad = (pad + c[3]) * 8.0f * FLT_EPSILON;
  struct RTCBounds *b = args->bounds_o;
  b->lower_x = c[0] - c[3] - pad;
  b->lower_y = c[1] - c[3] - pad;
  b->lower_z = c[2] - c[3] - pad;
  b->upper_x = c[0] + c[3] + pad;
  b->upper_y = c[1] + c[3] + pad;
  b->upper_z = c[2] + c[3] + pad;
}

/* The test's t for lane i of a ray record of n lanes (negative: a miss). */
static float user_sphere_t(const ember_scene *s, unsigned prim, void *ray, unsigned n,
                           unsigned i, const void *ctx) {
  float org[3], dir[3];
  for (int k = 0; k < 3; k++) {
    org[k] = EMBER_F(ray, k, n, i);
    dir[k] = EMBER_F(ray, 4 + k, n, i);
  }
  int leaving = skip_of(ctx, ray, n, i) == s->ntri + prim;
  return s->sphere_fn(org, dir, EMBER_F(ray, 3, n, i), EMBER_F(ray, EMBER_RAY_TFAR, n, i),
                      s->spheres + 4 * (size_t)prim, leaving);
}

static void user_sphere_intersect(const struct RTCIntersectFunctionNArguments *args) {
  const ember_scene *s = (const ember_scene *)args->geometryUserPtr;
  unsigned n = args->N;
  void *rh = args->rayhit;
  for (unsigned i = 0; i < n; i++) {
    if (args->valid[i] != -1) continue;
    float t = user_sphere_t(s, args->primID, rh, n, i, args->context);
    if (!(t >= 0.0f)) continue;
    EMBER_F(rh, EMBER_RAY_TFAR, n, i) = t;
    /* ember computes the normal itself: Ng is left zero, u and v unused. */
    for (int k = 0; k < 5; k++) EMBER_F(rh, EMBER_HIT + k, n, i) = 0.0f;
    EMBER_U(rh, EMBER_HIT + 5, n, i) = args->primID;
    EMBER_U(rh, EMBER_HIT + 6, n, i) = args->geomID;
    EMBER_U(rh, EMBER_HIT + 7, n, i) = RTC_INVALID_GEOMETRY_ID;
  }
}

static void user_sphere_occluded(const struct RTCOccludedFunctionNArguments *args) {
  const ember_scene *s = (const ember_scene *)args->geometryUserPtr;
  unsigned n = args->N;
  for (unsigned i = 0; i < n; i++) {
    if (args->valid[i] != -1) continue;
    if (user_sphere_t(s, args->primID, args->ray, n, i, args->context) >= 0.0f)
      EMBER_F(args->ray, EMBER_RAY_TFAR, n, i) = -INFINITY;
  }
}

static int attach_user_spheres(RTCDevice dev, RTCScene scene, ember_scene *s,
                               const float *spheres, size_t nsph) {
  s->user_spheres = (float *)malloc(nsph * 4 * sizeof(float));
  if (!s->user_spheres) return 0;
  memcpy(s->user_spheres, spheres, nsph * 4 * sizeof(float));
  s->spheres = s->user_spheres;
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_USER);
  if (!g) return 0;
  rtcSetGeometryUserPrimitiveCount(g, (unsigned)nsph);
  rtcSetGeometryUserData(g, s);
  rtcSetGeometryBoundsFunction(g, user_sphere_bounds, s);
  rtcSetGeometryIntersectFunction(g, user_sphere_intersect);
  rtcSetGeometryOccludedFunction(g, user_sphere_occluded);
  rtcCommitGeometry(g);
  rtcAttachGeometryByID(scene, g, EMBER_SPH_GEOM_ID);
  rtcReleaseGeometry(g);
  return 1;
}

static enum RTCBuildQuality to_quality(int q) {
  switch (q) {
  case EMBER_QUALITY_LOW: return RTC_BUILD_QUALITY_LOW;
  case EMBER_QUALITY_HIGH: return RTC_BUILD_QUALITY_HIGH;
  default: return RTC_BUILD_QUALITY_MEDIUM;
  }
}

static void free_scene(ember_scene *s) {
  if (s->scene) rtcReleaseScene(s->scene);
  free(s->user_spheres);
  free(s);
}

ember_scene *ember_scene_new(ember_device *d, const float *vertices, size_t nvert,
                             const uint32_t *indices, size_t ntri, const float *spheres,
                             size_t nsph, const ember_scene_options *o) {
  if (ntri > 0xFFFFFFF0u || nsph > 0xFFFFFFF0u - ntri) {
    on_error(d, RTC_ERROR_INVALID_ARGUMENT, "too many primitives for 32-bit ids");
    return NULL;
  }
  ember_scene *s = (ember_scene *)calloc(1, sizeof *s);
  if (!s) {
    on_error(d, RTC_ERROR_OUT_OF_MEMORY, "scene handle");
    return NULL;
  }
  RTCDevice dev = d->device;
  s->scene = rtcNewScene(dev);
  if (!s->scene) {
    free_scene(s);
    return NULL;
  }
  s->ntri = (uint32_t)ntri;
  s->queries = o->queries;
  s->self_hits = o->self_hits;
  s->sphere_fn = o->sphere;
  rtcSetSceneBuildQuality(s->scene, to_quality(o->quality));
  /* The filter flag only lets a query's own filter run; queries without one trace as
   * before. Without a filter in the mode the flag is left off. */
  int flags = o->robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE;
  if (o->self_hits != EMBER_SELF_OFFSET) flags |= EMBER_SCENE_FLAG_FILTER;
  rtcSetSceneFlags(s->scene, (enum RTCSceneFlags)flags);
  int ok = 1;
  if (ntri > 0 && nvert > 0)
    ok = ok && attach_triangles(dev, s->scene, vertices, nvert, indices, ntri);
  if (nsph > 0)
    ok = ok && (o->sphere ? attach_user_spheres(dev, s->scene, s, spheres, nsph)
                          : attach_spheres(dev, s->scene, s, spheres, nsph));
  if (ok) rtcCommitScene(s->scene);
  if (!ok || rtcGetDeviceError(dev) != RTC_ERROR_NONE) {
    free_scene(s);
    return NULL;
  }
  s->flags = (int)rtcGetSceneFlags(s->scene);
  return s;
}

int ember_scene_flags(const ember_scene *s) { return s->flags; }

_Static_assert(RTC_SCENE_FLAG_ROBUST == EMBER_SCENE_FLAG_ROBUST, "shim.h mirrors the flag");

void ember_scene_release(ember_scene *s) {
  if (s) free_scene(s);
}

/* ---- the skip filter ---- */

/* Whether the candidate hit `i` of a ray spawned from Embree sphere `sph` is its far
 * side: the origin is not outside the sphere (beyond the rounding of c, as in the
 * native test) and the hit lies past the middle of the chord. */
static int far_side_of_own_sphere(const ember_scene *s, unsigned sph,
                                  const struct RTCFilterFunctionNArguments *args, unsigned i) {
  const float *c = s->spheres + 4 * (size_t)sph;
  unsigned n = args->N;
  float f[3], d[3];
  for (int k = 0; k < 3; k++) {
    f[k] = EMBER_F(args->ray, k, n, i) - c[k];
    d[k] = EMBER_F(args->ray, 4 + k, n, i);
  }
  float ff = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
  float r2 = c[3] * c[3];
  /* gamma(8) of ember's native sphere test. */
  const float g8 = 8.0f * (FLT_EPSILON * 0.5f) / (1.0f - 8.0f * (FLT_EPSILON * 0.5f));
  if (ff - r2 > g8 * (ff + r2)) return 0;
  float a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  float b = f[0] * d[0] + f[1] * d[1] + f[2] * d[2];
  return b < 0.0f && EMBER_F(args->ray, EMBER_RAY_TFAR, n, i) * a >= -b;
}

/* Rejects hits on the primitive a ray was spawned from (see ember_ray.skip). During
 * the filter the ray's tfar holds the candidate hit's distance. User spheres never
 * reach it: their test applies the skip itself. */
static void skip_filter(const struct RTCFilterFunctionNArguments *args) {
  const skip_context *sc = (const skip_context *)args->context;
  for (unsigned i = 0; i < args->N; i++) {
    if (args->valid[i] != -1) continue;
    uint32_t skip = skip_of(sc, args->ray, args->N, i);
    unsigned geom = EMBER_U(args->hit, 6, args->N, i);
    unsigned prim = EMBER_U(args->hit, 5, args->N, i);
    if (geom == EMBER_TRI_GEOM_ID) {
      if (prim == skip) args->valid[i] = 0;
    } else if (sc->scene->ntri + prim == skip &&
               !far_side_of_own_sphere(sc->scene, prim, args, i)) {
      args->valid[i] = 0;
    }
  }
}

/* Whether a ray skipping `skip` needs the filter: only when the skip is a triangle or
 * an Embree sphere (user spheres apply their own skip). */
static int needs_filter(const ember_scene *s, uint32_t skip) {
  return skip != EMBER_NO_PRIM && (skip < s->ntri || !s->sphere_fn);
}

/* ---- single rays ---- */

static void fill_ray(struct RTCRay *r, const float org[3], const float dir[3], float tnear,
                     float tfar) {
  r->org_x = org[0];
  r->org_y = org[1];
  r->org_z = org[2];
  /* Embree requires tnear >= 0. A hit at exactly t = 0 means the origin lies on the
   * surface (a bounce ray off an axis-aligned plane at coordinate 0 gets no offset from
   * its zero error bound); ember never means such a hit, and the native test too starts
   * the interval at the smallest positive normal float. */
  r->tnear = tnear > FLT_MIN ? tnear : FLT_MIN;
  r->dir_x = dir[0];
  r->dir_y = dir[1];
  r->dir_z = dir[2];
  r->time = 0.0f;
  r->tfar = tfar;
  /* Debian builds Embree with ray masks: mask 0 would silently miss everything. */
  r->mask = 0xFFFFFFFFu;
  r->id = 0;
  r->flags = 0;
}

/* Embree's answer as ember's: the ember id of the primitive hit, t, normal, u, v. */
static int fill_hit(const ember_scene *s, unsigned geom, unsigned prim, float t, float ngx,
                    float ngy, float ngz, float u, float v, ember_hit *hit) {
  if (geom == RTC_INVALID_GEOMETRY_ID) {
    hit->prim = EMBER_NO_PRIM;
    return 0;
  }
  hit->t = t;
  hit->ng[0] = ngx;
  hit->ng[1] = ngy;
  hit->ng[2] = ngz;
  if (geom == EMBER_TRI_GEOM_ID) {
    hit->prim = prim;
    hit->u = u;
    hit->v = v;
  } else {
    hit->prim = s->ntri + prim;
    hit->u = 0.0f;
    hit->v = 0.0f;
  }
  return 1;
}

/* A ray as the single-ray functions take it. */
typedef struct one_ray {
  float org[3];
  float dir[3];
  float tnear;
  float tfar;
  uint32_t skip;
} one_ray;

/* One rtcIntersect1, with or without the skip filter. */
static int intersect1(const ember_scene *s, const one_ray *ray, int filtered, ember_hit *hit) {
  union {
    struct RTCRayHit rh;
    char room[sizeof(struct RTCRayHit) + EMBER_HIT_SLACK];
  } record EMBER_ALIGN;
  struct RTCRayHit *rhp = &record.rh;
  fill_ray(&rhp->ray, ray->org, ray->dir, ray->tnear, ray->tfar);
  rhp->hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rhp->hit.primID = RTC_INVALID_GEOMETRY_ID;
  rhp->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  skip_context sc;
  init_skip_context(&sc, s, ray->skip, NULL);
#if RTC_VERSION_MAJOR >= 4
  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  args.context = &sc.ctx;
  args.filter = filtered ? skip_filter : NULL;
  rtcIntersect1(s->scene, rhp, &args);
#else
  sc.ctx.filter = filtered ? skip_filter : NULL;
  rtcIntersect1(s->scene, &sc.ctx, rhp);
#endif
  return fill_hit(s, rhp->hit.geomID, rhp->hit.primID, rhp->ray.tfar, rhp->hit.Ng_x,
                  rhp->hit.Ng_y, rhp->hit.Ng_z, rhp->hit.u, rhp->hit.v, hit);
}

static int occluded1(const ember_scene *s, const one_ray *ray, int filtered) {
  struct RTCRay r EMBER_ALIGN;
  fill_ray(&r, ray->org, ray->dir, ray->tnear, ray->tfar);
  skip_context sc;
  init_skip_context(&sc, s, ray->skip, NULL);
#if RTC_VERSION_MAJOR >= 4
  struct RTCOccludedArguments args;
  rtcInitOccludedArguments(&args);
  args.context = &sc.ctx;
  args.filter = filtered ? skip_filter : NULL;
  rtcOccluded1(s->scene, &r, &args);
#else
  sc.ctx.filter = filtered ? skip_filter : NULL;
  rtcOccluded1(s->scene, &sc.ctx, &r);
#endif
  /* A hit is reported by tfar = -inf; no hit data is filled. */
  return r.tfar == -INFINITY;
}

/* A ray with the scene's self-hit policy. */
static int intersect_one(const ember_scene *s, const one_ray *ray, ember_hit *hit) {
  int filter = needs_filter(s, ray->skip);
  switch (s->self_hits) {
  case EMBER_SELF_OFFSET: return intersect1(s, ray, 0, hit);
  case EMBER_SELF_RETRY:
    if (intersect1(s, ray, 0, hit) && !(filter && hit->prim == ray->skip)) return 1;
    if (!filter || hit->prim == EMBER_NO_PRIM) return 0;
    /* The nearest hit is the primitive left (or, for an Embree sphere, maybe its far
     * side): the filter decides, so the answer is the filter's. */
    return intersect1(s, ray, 1, hit);
  default: return intersect1(s, ray, filter, hit);
  }
}

static int occluded_one(const ember_scene *s, const one_ray *ray) {
  return occluded1(s, ray, s->self_hits != EMBER_SELF_OFFSET && needs_filter(s, ray->skip));
}

static one_ray from_ember_ray(const ember_ray *r) {
  one_ray o = {{r->org[0], r->org[1], r->org[2]}, {r->dir[0], r->dir[1], r->dir[2]},
               r->tnear, r->tfar, r->skip};
  return o;
}

int ember_intersect1(const ember_scene *s, const ember_ray *ray, ember_hit *hit) {
  one_ray r = from_ember_ray(ray);
  return intersect_one(s, &r, hit);
}

int ember_occluded1(const ember_scene *s, const ember_ray *ray) {
  one_ray r = from_ember_ray(ray);
  return occluded_one(s, &r);
}

/* ---- packets ---- */

/* The query context of a packet or stream: Embree 3 takes it before the rays,
 * Embree 4 in optional arguments after them. `skips` by ray id; `filtered`: run the
 * skip filter; `coherent`: Embree's coherent flag. */
#if RTC_VERSION_MAJOR >= 4
#define EMBER_QUERY(fn, args_type, init, valid, s, rays, skips, filtered, coherent)         \
  do {                                                                                     \
    skip_context sc;                                                                       \
    init_skip_context(&sc, s, EMBER_NO_PRIM, skips);                                       \
    struct args_type args;                                                                 \
    init(&args);                                                                           \
    args.context = &sc.ctx;                                                                \
    args.filter = (filtered) ? skip_filter : NULL;                                         \
    if (coherent) args.flags = RTC_RAY_QUERY_FLAG_COHERENT;                                \
    fn(valid, s->scene, rays, &args);                                                      \
  } while (0)
#define EMBER_INTERSECT_PACKET(N, valid, s, rh, skips, filtered, coherent)                 \
  EMBER_QUERY(rtcIntersect##N, RTCIntersectArguments, rtcInitIntersectArguments, valid, s, rh, \
              skips, filtered, coherent)
#define EMBER_OCCLUDED_PACKET(N, valid, s, r, skips, filtered, coherent)                   \
  EMBER_QUERY(rtcOccluded##N, RTCOccludedArguments, rtcInitOccludedArguments, valid, s, r,  \
              skips, filtered, coherent)
#else
#define EMBER_QUERY(fn, valid, s, rays, skips, filtered, coherent)                         \
  do {                                                                                     \
    skip_context sc;                                                                       \
    init_skip_context(&sc, s, EMBER_NO_PRIM, skips);                                       \
    sc.ctx.filter = (filtered) ? skip_filter : NULL;                                       \
    if (coherent) sc.ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;                      \
    fn(valid, s->scene, &sc.ctx, rays);                                                    \
  } while (0)
#define EMBER_INTERSECT_PACKET(N, valid, s, rh, skips, filtered, coherent)                 \
  EMBER_QUERY(rtcIntersect##N, valid, s, rh, skips, filtered, coherent)
#define EMBER_OCCLUDED_PACKET(N, valid, s, r, skips, filtered, coherent)                   \
  EMBER_QUERY(rtcOccluded##N, valid, s, r, skips, filtered, coherent)
#endif

/* Lane i of an ember packet as a single ray. */
static one_ray lane_ray(const ember_packet *p, unsigned i) {
  one_ray r = {{p->org[i], p->org[EMBER_LANES + i], p->org[2 * EMBER_LANES + i]},
               {p->dir[i], p->dir[EMBER_LANES + i], p->dir[2 * EMBER_LANES + i]},
               0.0f, p->tfar[i], p->skip[i]};
  return r;
}

static void write_lane(const ember_packet_hits *h, unsigned i, const ember_hit *e, int found) {
  h->t[i] = found ? e->t : INFINITY;
  h->prim[i] = found ? e->prim : EMBER_NO_PRIM;
  h->u[i] = found ? e->u : 0.0f;
  h->v[i] = found ? e->v : 0.0f;
}

/* Fills lanes [first, first + n) of Embree packet record `r` (RTCRayN layout) from
 * ember packet lanes `lanes`, and their valid mask: field by field, as fill_ray sets a
 * single ray (tnear the smallest normal float, every mask bit, the lane as ray id). */
static inline void fill_packet(void *r, int *valid, unsigned n, const ember_packet *p,
                               unsigned first, uint32_t lanes) {
  float *f = (float *)r;
  unsigned *u = (unsigned *)r;
  for (unsigned k = 0; k < 3; k++) {
    memcpy(f + k * n, p->org + k * EMBER_LANES + first, n * sizeof(float));
    memcpy(f + (4 + k) * n, p->dir + k * EMBER_LANES + first, n * sizeof(float));
  }
  memcpy(f + EMBER_RAY_TFAR * n, p->tfar + first, n * sizeof(float));
  for (unsigned i = 0; i < n; i++) {
    f[3 * n + i] = FLT_MIN;
    f[7 * n + i] = 0.0f;
    u[9 * n + i] = 0xFFFFFFFFu;
    u[EMBER_RAY_ID * n + i] = first + i;
    u[11 * n + i] = 0;
    valid[i] = (lanes >> (first + i) & 1) ? -1 : 0;
  }
}

/* Sets the hit records of a packet record of n lanes to "no hit". */
static void clear_hits(void *rh, unsigned n) {
  for (unsigned i = 0; i < n; i++) {
    EMBER_U(rh, EMBER_HIT + 5, n, i) = RTC_INVALID_GEOMETRY_ID;
    EMBER_U(rh, EMBER_HIT + 6, n, i) = RTC_INVALID_GEOMETRY_ID;
    EMBER_U(rh, EMBER_HIT + 7, n, i) = RTC_INVALID_GEOMETRY_ID;
  }
}

/* Reads lane i of a packet record of n lanes back as ember's hit. */
static int read_hit(const ember_scene *s, void *rh, unsigned n, unsigned i, ember_hit *e) {
  return fill_hit(s, EMBER_U(rh, EMBER_HIT + 6, n, i), EMBER_U(rh, EMBER_HIT + 5, n, i),
                  EMBER_F(rh, EMBER_RAY_TFAR, n, i), EMBER_F(rh, EMBER_HIT, n, i),
                  EMBER_F(rh, EMBER_HIT + 1, n, i), EMBER_F(rh, EMBER_HIT + 2, n, i),
                  EMBER_F(rh, EMBER_HIT + 3, n, i), EMBER_F(rh, EMBER_HIT + 4, n, i), e);
}

/* Whether any lane of `lanes` has a skip the filter must apply. */
static int lanes_need_filter(const ember_scene *s, const ember_packet *p, uint32_t lanes) {
  if (s->self_hits == EMBER_SELF_OFFSET) return 0;
  for (uint32_t m = lanes; m; m &= m - 1)
    if (needs_filter(s, p->skip[__builtin_ctz(m)])) return 1;
  return 0;
}

/* Whether a packet of `lanes` runs the skip filter: under EMBER_SELF_FILTER when a
 * lane needs it; under EMBER_SELF_RETRY only for occlusion (intersection lanes that
 * found their own triangle are traced again alone, with it). */
static int packet_filtered(const ember_scene *s, const ember_packet *p, uint32_t lanes,
                           int occlusion) {
  if (s->self_hits == EMBER_SELF_RETRY && !occlusion) return 0;
  return lanes_need_filter(s, p, lanes);
}

/* rtcIntersect<N> over lanes [first, first + N) of `lanes`. */
#define EMBER_PACKET_LANES_FN(N)                                                           \
  static void intersect_lanes##N(const ember_scene *s, const ember_packet *p, unsigned first, \
                                 uint32_t lanes, int coherent, const ember_packet_hits *h) { \
    union {                                                                                \
      struct RTCRayHit##N rh;                                                              \
      char room[sizeof(struct RTCRayHit##N) + EMBER_HIT_SLACK];                            \
    } record EMBER_ALIGN;                                                                  \
    int valid[N] EMBER_ALIGN;                                                              \
    fill_packet(&record.rh, valid, N, p, first, lanes);                                    \
    clear_hits(&record.rh, N);                                                             \
    EMBER_INTERSECT_PACKET(N, valid, s, &record.rh, p->skip, packet_filtered(s, p, lanes, 0), \
                           coherent);                                                      \
    for (unsigned i = 0; i < N; i++) {                                                     \
      unsigned l = first + i;                                                              \
      if (!(lanes >> l & 1)) continue;                                                     \
      ember_hit e;                                                                         \
      int found = read_hit(s, &record.rh, N, i, &e);                                       \
      if (found && s->self_hits == EMBER_SELF_RETRY && e.prim == p->skip[l] &&             \
          needs_filter(s, p->skip[l])) {                                                   \
        one_ray r = lane_ray(p, l);                                                        \
        found = intersect1(s, &r, 1, &e);                                                  \
      }                                                                                    \
      write_lane(h, l, &e, found);                                                         \
    }                                                                                      \
  }

EMBER_PACKET_LANES_FN(8)
EMBER_PACKET_LANES_FN(16)

/* rtcOccluded<N> over lanes [first, first + N) of `lanes`: the occluded ones. */
#define EMBER_OCCLUDED_LANES_FN(N)                                                         \
  static uint32_t occluded_lanes##N(const ember_scene *s, const ember_packet *p,          \
                                    unsigned first, uint32_t lanes, int coherent) {       \
    struct RTCRay##N r EMBER_ALIGN;                                                        \
    int valid[N] EMBER_ALIGN;                                                              \
    fill_packet(&r, valid, N, p, first, lanes);                                            \
    EMBER_OCCLUDED_PACKET(N, valid, s, &r, p->skip, packet_filtered(s, p, lanes, 1),       \
                          coherent);                                                       \
    uint32_t occluded = 0;                                                                 \
    for (unsigned i = 0; i < N; i++)                                                       \
      if ((lanes >> (first + i) & 1) && r.tfar[i] == -INFINITY) occluded |= 1u << (first + i); \
    return occluded;                                                                       \
  }

EMBER_OCCLUDED_LANES_FN(8)
EMBER_OCCLUDED_LANES_FN(16)

static void intersect_singles(const ember_scene *s, const ember_packet *p, uint32_t lanes,
                              const ember_packet_hits *h) {
  for (uint32_t m = lanes; m; m &= m - 1) {
    unsigned i = (unsigned)__builtin_ctz(m);
    one_ray r = lane_ray(p, i);
    ember_hit e;
    write_lane(h, i, &e, intersect_one(s, &r, &e));
  }
}

static uint32_t occluded_singles(const ember_scene *s, const ember_packet *p, uint32_t lanes) {
  uint32_t occluded = 0;
  for (uint32_t m = lanes; m; m &= m - 1) {
    unsigned i = (unsigned)__builtin_ctz(m);
    one_ray r = lane_ray(p, i);
    if (occluded_one(s, &r)) occluded |= 1u << i;
  }
  return occluded;
}

#if RTC_VERSION_MAJOR < 4
/* The active lanes as one Embree 3 stream of single rays (array of RTCRayHit). */
static void stream_lanes(const ember_scene *s, const ember_packet *p, uint32_t lanes,
                         const ember_packet_hits *h, uint32_t *occluded) {
  struct RTCRayHit recs[EMBER_LANES] EMBER_ALIGN;
  unsigned n = 0;
  int retry = s->self_hits == EMBER_SELF_RETRY && !occluded;
  int filtered = !retry && lanes_need_filter(s, p, lanes);
  for (uint32_t m = lanes; m; m &= m - 1) {
    one_ray r = lane_ray(p, (unsigned)__builtin_ctz(m));
    fill_ray(&recs[n].ray, r.org, r.dir, 0.0f, r.tfar);
    /* The lane number: the filter and the user spheres find its skip by it. */
    recs[n].ray.id = (unsigned)__builtin_ctz(m);
    recs[n].hit.geomID = RTC_INVALID_GEOMETRY_ID;
    recs[n].hit.primID = RTC_INVALID_GEOMETRY_ID;
    recs[n].hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    n++;
  }
  skip_context sc;
  init_skip_context(&sc, s, EMBER_NO_PRIM, p->skip);
  sc.ctx.filter = filtered ? skip_filter : NULL;
  if (occluded) {
    rtcOccluded1M(s->scene, &sc.ctx, &recs[0].ray, n, sizeof recs[0]);
    *occluded = 0;
    for (unsigned k = 0; k < n; k++)
      if (recs[k].ray.tfar == -INFINITY) *occluded |= 1u << recs[k].ray.id;
    return;
  }
  rtcIntersect1M(s->scene, &sc.ctx, &recs[0], n, sizeof recs[0]);
  for (unsigned k = 0; k < n; k++) {
    struct RTCRayHit *r = &recs[k];
    unsigned i = r->ray.id;
    ember_hit e;
    int found = fill_hit(s, r->hit.geomID, r->hit.primID, r->ray.tfar, r->hit.Ng_x,
                         r->hit.Ng_y, r->hit.Ng_z, r->hit.u, r->hit.v, &e);
    if (retry && found && e.prim == p->skip[i] && needs_filter(s, p->skip[i])) {
      one_ray one = lane_ray(p, i);
      found = intersect1(s, &one, 1, &e);
    }
    write_lane(h, i, &e, found);
  }
}
#endif

void ember_intersect16(const ember_scene *s, const ember_packet *p, uint32_t active,
                       const ember_packet_hits *h) {
  if (!active) return;
  switch (s->queries) {
  case EMBER_QUERIES_PACKET16:
    intersect_lanes16(s, p, 0, active, 0, h);
    return;
  case EMBER_QUERIES_PACKET8:
  case EMBER_QUERIES_PACKET8_COHERENT:
    for (unsigned half = 0; half < 2; half++) {
      uint32_t lanes = active & (0xFFu << (8 * half));
      if (lanes) intersect_lanes8(s, p, 8 * half, lanes, s->queries == EMBER_QUERIES_PACKET8_COHERENT, h);
    }
    return;
#if RTC_VERSION_MAJOR < 4
  case EMBER_QUERIES_STREAM:
    stream_lanes(s, p, active, h, NULL);
    return;
#endif
  case EMBER_QUERIES_CAMERA8: {
    uint32_t camera = 0;
    for (uint32_t m = active; m; m &= m - 1)
      if (p->skip[__builtin_ctz(m)] == EMBER_NO_PRIM) camera |= 1u << __builtin_ctz(m);
    for (unsigned half = 0; half < 2; half++) {
      uint32_t lanes = camera & (0xFFu << (8 * half));
      if (__builtin_popcount(lanes) < 2) continue;
      intersect_lanes8(s, p, 8 * half, lanes, 1, h);
      active &= ~lanes;
    }
    intersect_singles(s, p, active, h);
    return;
  }
  default:
    intersect_singles(s, p, active, h);
  }
}

uint32_t ember_occluded16(const ember_scene *s, const ember_packet *p, uint32_t active) {
  if (!active) return 0;
  switch (s->queries) {
  case EMBER_QUERIES_PACKET16: return occluded_lanes16(s, p, 0, active, 0);
  case EMBER_QUERIES_PACKET8:
  case EMBER_QUERIES_PACKET8_COHERENT: {
    uint32_t occluded = 0;
    for (unsigned half = 0; half < 2; half++) {
      uint32_t lanes = active & (0xFFu << (8 * half));
      if (lanes)
        occluded |= occluded_lanes8(s, p, 8 * half, lanes,
                                    s->queries == EMBER_QUERIES_PACKET8_COHERENT);
    }
    return occluded;
  }
#if RTC_VERSION_MAJOR < 4
  case EMBER_QUERIES_STREAM: {
    uint32_t occluded = 0;
    stream_lanes(s, p, active, NULL, &occluded);
    return occluded;
  }
#endif
  default: return occluded_singles(s, p, active);
  }
}

/* Camera rays (no skips) as coherent packets of 4, 8 or 16: the bench's and tests'
 * packet queries. */
#define EMBER_PACKET_FN(N)                                                                 \
  static int intersect_packet##N(const ember_scene *s, const ember_ray *rays, size_t n,   \
                                 ember_hit *hits) {                                        \
    union {                                                                                \
      struct RTCRayHit##N rh;                                                              \
      char room[sizeof(struct RTCRayHit##N) + EMBER_HIT_SLACK];                            \
    } record EMBER_ALIGN;                                                                  \
    int valid[N] EMBER_ALIGN;                                                              \
    float org[3][EMBER_LANES], dir[3][EMBER_LANES], tfar[EMBER_LANES];                     \
    uint32_t skip[EMBER_LANES];                                                            \
    for (unsigned i = 0; i < N; i++) {                                                     \
      const ember_ray *r = &rays[i < n ? i : 0];                                           \
      for (int k = 0; k < 3; k++) {                                                        \
        org[k][i] = r->org[k];                                                             \
        dir[k][i] = r->dir[k];                                                             \
      }                                                                                    \
      tfar[i] = r->tfar;                                                                   \
      skip[i] = EMBER_NO_PRIM;                                                             \
    }                                                                                      \
    ember_packet p = {&org[0][0], &dir[0][0], tfar, skip};                                 \
    uint32_t lanes = (uint32_t)((1ull << n) - 1);                                          \
    fill_packet(&record.rh, valid, N, &p, 0, lanes);                                       \
    clear_hits(&record.rh, N);                                                             \
    EMBER_INTERSECT_PACKET(N, valid, s, &record.rh, skip, 0, 1);                           \
    int count = 0;                                                                         \
    for (unsigned i = 0; i < n; i++) count += read_hit(s, &record.rh, N, i, &hits[i]);      \
    return count;                                                                          \
  }

EMBER_PACKET_FN(4)
EMBER_PACKET_FN(8)
EMBER_PACKET_FN(16)

int ember_intersect_packet(const ember_scene *s, int width, const ember_ray *rays, size_t n,
                           ember_hit *hits) {
  if (n == 0 || n > (size_t)width) return -1;
  switch (width) {
  case 4: return intersect_packet4(s, rays, n, hits);
  case 8: return intersect_packet8(s, rays, n, hits);
  case 16: return intersect_packet16(s, rays, n, hits);
  default: return -1;
  }
}
