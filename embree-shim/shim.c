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
  /* The spheres (x, y, z, r), in the sphere geometry's own buffer, for the skip filter. */
  const float *spheres;
};

#if RTC_VERSION_MAJOR >= 4
typedef struct RTCRayQueryContext ember_rtc_context;
#define EMBER_SCENE_FLAG_FILTER RTC_SCENE_FLAG_FILTER_FUNCTION_IN_ARGUMENTS
#else
typedef struct RTCIntersectContext ember_rtc_context;
#define EMBER_SCENE_FLAG_FILTER RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION
#endif

/* Embree's context, extended with what the skip filter needs: Embree hands the filter
 * the context pointer it was given, so the filter can reach the fields after it. */
typedef struct skip_context {
  ember_rtc_context ctx;
  const ember_scene *scene;
  uint32_t skip;
  /* Packets: the primitive each ray skips, by ray id (NULL for single rays). */
  const uint32_t *skips;
} skip_context;

/* A fresh Embree context carrying what the skip filter needs: the primitive a single
 * ray skips, or per ray id the primitives a packet's rays skip. */
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

static int attach_spheres(RTCDevice dev, RTCScene scene, const float *spheres, size_t nsph,
                          const float **kept) {
  RTCGeometry g = rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_SPHERE_POINT);
  if (!g) return 0;
  float *vb = (float *)rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                               4 * sizeof(float), nsph);
  if (!vb) {
    rtcReleaseGeometry(g);
    return 0;
  }
  memcpy(vb, spheres, nsph * 4 * sizeof(float));
  *kept = vb;
  enable_query_filter(g);
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

ember_scene *ember_scene_new(ember_device *d, const float *vertices, size_t nvert,
                             const uint32_t *indices, size_t ntri, const float *spheres,
                             size_t nsph, int quality, int robust) {
  if (ntri > 0xFFFFFFF0u || nsph > 0xFFFFFFF0u - ntri) {
    on_error(d, RTC_ERROR_INVALID_ARGUMENT, "too many primitives for 32-bit ids");
    return NULL;
  }
  RTCDevice dev = d->device;
  RTCScene scene = rtcNewScene(dev);
  if (!scene) return NULL;
  rtcSetSceneBuildQuality(scene, to_quality(quality));
  /* The filter flag only lets a query's own filter run; queries without one (camera
   * and other unspawned rays) trace as before. */
  int flags = EMBER_SCENE_FLAG_FILTER | (robust ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
  rtcSetSceneFlags(scene, (enum RTCSceneFlags)flags);
  int ok = 1;
  const float *kept_spheres = NULL;
  if (ntri > 0 && nvert > 0) ok = ok && attach_triangles(dev, scene, vertices, nvert, indices, ntri);
  if (nsph > 0) ok = ok && attach_spheres(dev, scene, spheres, nsph, &kept_spheres);
  if (ok) rtcCommitScene(scene);
  if (!ok || rtcGetDeviceError(dev) != RTC_ERROR_NONE) {
    rtcReleaseScene(scene);
    return NULL;
  }
  ember_scene *s = (ember_scene *)calloc(1, sizeof *s);
  if (!s) {
    rtcReleaseScene(scene);
    on_error(d, RTC_ERROR_OUT_OF_MEMORY, "scene handle");
    return NULL;
  }
  s->scene = scene;
  s->ntri = (uint32_t)ntri;
  s->flags = (int)rtcGetSceneFlags(scene);
  s->spheres = kept_spheres;
  return s;
}

int ember_scene_flags(const ember_scene *s) { return s->flags; }

_Static_assert(RTC_SCENE_FLAG_ROBUST == EMBER_SCENE_FLAG_ROBUST, "shim.h mirrors the flag");

void ember_scene_release(ember_scene *s) {
  if (!s) return;
  rtcReleaseScene(s->scene);
  free(s);
}

static void fill_ray(struct RTCRay *r, const ember_ray *in) {
  r->org_x = in->org[0];
  r->org_y = in->org[1];
  r->org_z = in->org[2];
  /* Embree requires tnear >= 0. A hit at exactly t = 0 means the origin lies on the
   * surface (a bounce ray off an axis-aligned plane at coordinate 0 gets no offset from
   * its zero error bound); ember never means such a hit, and the native test too starts
   * the interval at the smallest positive normal float. */
  r->tnear = in->tnear > FLT_MIN ? in->tnear : FLT_MIN;
  r->dir_x = in->dir[0];
  r->dir_y = in->dir[1];
  r->dir_z = in->dir[2];
  r->time = 0.0f;
  r->tfar = in->tfar;
  /* Debian builds Embree with ray masks: mask 0 would silently miss everything. */
  r->mask = 0xFFFFFFFFu;
  r->id = 0;
  r->flags = 0;
}

/* Field k of lane i of Embree's packets of runtime size n (rtcore_ray.h's RTCRayN_* and
 * RTCHitN_* helpers exist only for C++): rays hold org xyz, tnear, dir xyz, time, tfar;
 * hits Ng xyz, u, v, primID, geomID, in that order, each as n consecutive lanes. */
#define EMBER_RAYN(ray, k, n, i) (((const float *)(ray))[(k) * (n) + (i)])
#define EMBER_RAYN_ID(ray, n, i) (((const unsigned *)(ray))[10 * (n) + (i)])
#define EMBER_HITN_PRIM(hit, n, i) (((const unsigned *)(hit))[5 * (n) + (i)])
#define EMBER_HITN_GEOM(hit, n, i) (((const unsigned *)(hit))[6 * (n) + (i)])

/* Whether the candidate hit `i` of a ray spawned from sphere `sph` is its far side:
 * the origin is not outside the sphere (beyond the rounding of c, as in the native
 * test) and the hit lies past the middle of the chord. */
static int far_side_of_own_sphere(const ember_scene *s, unsigned sph,
                                  const struct RTCFilterFunctionNArguments *args, unsigned i) {
  const float *c = s->spheres + 4 * (size_t)sph;
  unsigned n = args->N;
  float f[3], d[3];
  for (int k = 0; k < 3; k++) {
    f[k] = EMBER_RAYN(args->ray, k, n, i) - c[k];
    d[k] = EMBER_RAYN(args->ray, 4 + k, n, i);
  }
  float ff = f[0] * f[0] + f[1] * f[1] + f[2] * f[2];
  float r2 = c[3] * c[3];
  /* gamma(8) of ember's native sphere test. */
  const float g8 = 8.0f * (FLT_EPSILON * 0.5f) / (1.0f - 8.0f * (FLT_EPSILON * 0.5f));
  if (ff - r2 > g8 * (ff + r2)) return 0;
  float a = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
  float b = f[0] * d[0] + f[1] * d[1] + f[2] * d[2];
  return b < 0.0f && EMBER_RAYN(args->ray, 8, n, i) * a >= -b;
}

/* Rejects hits on the primitive a ray was spawned from (see ember_ray.skip). During
 * the filter the ray's tfar holds the candidate hit's distance. */
static void skip_filter(const struct RTCFilterFunctionNArguments *args) {
  const skip_context *sc = (const skip_context *)args->context;
  for (unsigned i = 0; i < args->N; i++) {
    if (args->valid[i] != -1) continue;
    uint32_t skip = sc->skips ? sc->skips[EMBER_RAYN_ID(args->ray, args->N, i)] : sc->skip;
    unsigned geom = EMBER_HITN_GEOM(args->hit, args->N, i);
    unsigned prim = EMBER_HITN_PRIM(args->hit, args->N, i);
    if (geom == EMBER_TRI_GEOM_ID) {
      if (prim == skip) args->valid[i] = 0;
    } else if (sc->scene->ntri + prim == skip &&
               !far_side_of_own_sphere(sc->scene, prim, args, i)) {
      args->valid[i] = 0;
    }
  }
}

/* Embree fills a hit from its ray and hit records: shared by single rays and packets. */
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

int ember_intersect1(const ember_scene *s, const ember_ray *ray, ember_hit *hit) {
  union {
    struct RTCRayHit rh;
    char room[sizeof(struct RTCRayHit) + EMBER_HIT_SLACK];
  } record;
  struct RTCRayHit *rhp = &record.rh;
  fill_ray(&rhp->ray, ray);
  rhp->hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rhp->hit.primID = RTC_INVALID_GEOMETRY_ID;
  rhp->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
  skip_context sc;
  init_skip_context(&sc, s, ray->skip, NULL);
  int filtered = ray->skip != EMBER_NO_PRIM;
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

/* One packet function per width: structure-of-arrays rays, a valid mask (-1 on,
 * 0 off), then the same read-out as a single ray. Embree 3 takes a context before the
 * ray, Embree 4 optional arguments after it. */
#if RTC_VERSION_MAJOR >= 4
#define EMBER_TRACE_PACKET(N, valid, scene, rh)                                            \
  do {                                                                                     \
    struct RTCIntersectArguments args;                                                     \
    rtcInitIntersectArguments(&args);                                                      \
    rtcIntersect##N(valid, scene, rh, &args);                                              \
  } while (0)
#else
#define EMBER_TRACE_PACKET(N, valid, scene, rh)                                            \
  do {                                                                                     \
    struct RTCIntersectContext ctx;                                                        \
    rtcInitIntersectContext(&ctx);                                                         \
    rtcIntersect##N(valid, scene, &ctx, rh);                                               \
  } while (0)
#endif

#define EMBER_PACKET_FN(N)                                                                 \
  static int intersect_packet##N(const ember_scene *s, const ember_ray *rays, size_t n,   \
                                 ember_hit *hits) {                                        \
    union {                                                                                \
      struct RTCRayHit##N rh;                                                              \
      char room[sizeof(struct RTCRayHit##N) + EMBER_HIT_SLACK];                            \
    } record;                                                                              \
    struct RTCRayHit##N *rhp = &record.rh;                                                 \
    int valid[N];                                                                          \
    for (size_t i = 0; i < N; i++) {                                                       \
      struct RTCRay r;                                                                     \
      fill_ray(&r, &rays[i < n ? i : 0]);                                                  \
      valid[i] = i < n ? -1 : 0;                                                           \
      rhp->ray.org_x[i] = r.org_x;                                                         \
      rhp->ray.org_y[i] = r.org_y;                                                         \
      rhp->ray.org_z[i] = r.org_z;                                                         \
      rhp->ray.tnear[i] = r.tnear;                                                         \
      rhp->ray.dir_x[i] = r.dir_x;                                                         \
      rhp->ray.dir_y[i] = r.dir_y;                                                         \
      rhp->ray.dir_z[i] = r.dir_z;                                                         \
      rhp->ray.time[i] = r.time;                                                           \
      rhp->ray.tfar[i] = r.tfar;                                                           \
      rhp->ray.mask[i] = r.mask;                                                           \
      rhp->ray.id[i] = (unsigned)i;                                                        \
      rhp->ray.flags[i] = r.flags;                                                         \
      rhp->hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;                                        \
      rhp->hit.primID[i] = RTC_INVALID_GEOMETRY_ID;                                        \
      rhp->hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;                                     \
    }                                                                                      \
    EMBER_TRACE_PACKET(N, valid, s->scene, rhp);                                           \
    int count = 0;                                                                         \
    for (size_t i = 0; i < n; i++)                                                         \
      count += fill_hit(s, rhp->hit.geomID[i], rhp->hit.primID[i], rhp->ray.tfar[i],       \
                        rhp->hit.Ng_x[i], rhp->hit.Ng_y[i], rhp->hit.Ng_z[i],              \
                        rhp->hit.u[i], rhp->hit.v[i], &hits[i]);                           \
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

int ember_occluded1(const ember_scene *s, const ember_ray *ray) {
  struct RTCRay r;
  fill_ray(&r, ray);
  skip_context sc;
  init_skip_context(&sc, s, ray->skip, NULL);
  int filtered = ray->skip != EMBER_NO_PRIM;
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

/* Sixteen rays as one Embree packet, each skipping its own primitive: the lanes of
 * `active` are traced, ray ids are lane numbers (the filter finds a lane's skip by
 * its id). */
static void fill_packet16(const ember_ray *rays, uint32_t active, struct RTCRay16 *r,
                          int valid[16], uint32_t skips[16]) {
  for (unsigned i = 0; i < 16; i++) {
    struct RTCRay one;
    fill_ray(&one, &rays[i]);
    valid[i] = (active >> i & 1) ? -1 : 0;
    skips[i] = rays[i].skip;
    r->org_x[i] = one.org_x;
    r->org_y[i] = one.org_y;
    r->org_z[i] = one.org_z;
    r->tnear[i] = one.tnear;
    r->dir_x[i] = one.dir_x;
    r->dir_y[i] = one.dir_y;
    r->dir_z[i] = one.dir_z;
    r->time[i] = 0.0f;
    r->tfar[i] = one.tfar;
    r->mask[i] = one.mask;
    r->id[i] = i;
    r->flags[i] = 0;
  }
}

void ember_intersect16(const ember_scene *s, const ember_ray *rays, uint32_t active,
                       ember_hit *hits) {
  union {
    struct RTCRayHit16 rh;
    char room[sizeof(struct RTCRayHit16) + EMBER_HIT_SLACK];
  } record;
  struct RTCRayHit16 *rhp = &record.rh;
  int valid[16];
  uint32_t skips[16];
  fill_packet16(rays, active, &rhp->ray, valid, skips);
  for (unsigned i = 0; i < 16; i++) {
    rhp->hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
    rhp->hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
    rhp->hit.instID[0][i] = RTC_INVALID_GEOMETRY_ID;
  }
  skip_context sc;
  init_skip_context(&sc, s, EMBER_NO_PRIM, skips);
#if RTC_VERSION_MAJOR >= 4
  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  args.context = &sc.ctx;
  args.filter = skip_filter;
  rtcIntersect16(valid, s->scene, rhp, &args);
#else
  sc.ctx.filter = skip_filter;
  rtcIntersect16(valid, s->scene, &sc.ctx, rhp);
#endif
  for (unsigned i = 0; i < 16; i++)
    if (active >> i & 1)
      fill_hit(s, rhp->hit.geomID[i], rhp->hit.primID[i], rhp->ray.tfar[i], rhp->hit.Ng_x[i],
               rhp->hit.Ng_y[i], rhp->hit.Ng_z[i], rhp->hit.u[i], rhp->hit.v[i], &hits[i]);
}

uint32_t ember_occluded16(const ember_scene *s, const ember_ray *rays, uint32_t active) {
  struct RTCRay16 r;
  int valid[16];
  uint32_t skips[16];
  fill_packet16(rays, active, &r, valid, skips);
  skip_context sc;
  init_skip_context(&sc, s, EMBER_NO_PRIM, skips);
#if RTC_VERSION_MAJOR >= 4
  struct RTCOccludedArguments args;
  rtcInitOccludedArguments(&args);
  args.context = &sc.ctx;
  args.filter = skip_filter;
  rtcOccluded16(valid, s->scene, &r, &args);
#else
  sc.ctx.filter = skip_filter;
  rtcOccluded16(valid, s->scene, &sc.ctx, &r);
#endif
  uint32_t occluded = 0;
  for (unsigned i = 0; i < 16; i++)
    if ((active >> i & 1) && r.tfar[i] == -INFINITY) occluded |= 1u << i;
  return occluded;
}
