// Embree's own ray throughput on the `accel` bench's dumped rays, called from
// C++ with no binding in between: the configurations a C++ renderer would
// use, for scripts/bench_embree.py.
//
//   embree_rays DUMP SET INTERSECT|OCCLUDED WIDTH NONE|ROBUST RUNS SECONDS
//
// Builds against the Embree 3 that Mitsuba 3's wheel ships (its headers and
// libembree3.so, in Mitsuba's namespace), or with -DEMBREE4 against the Embree 4
// that `embreex`'s wheel ships (its libembree4, called through the declarations
// below: the wheel has no headers), with Mitsuba's scene settings
// (build quality HIGH), one thread. WIDTH 1: one rtcIntersect1/rtcOccluded1
// per ray; WIDTH 16: rtcIntersect16/rtcOccluded16 on 16 consecutive rays, the
// call Mitsuba's llvm_ad_rgb makes on AVX-512 machines. NONE is Mitsuba's
// scene flag (Embree's fastest tests); ROBUST asks for watertight triangle and
// conservative box tests, the guarantees gradtrace's queries keep. Timing as bench_embree's
// `time_passes`: the first pass apart, 1 s of warm-up, then passes for SECONDS
// (at least RUNS); prints one JSON line: median_s, first_s, build_s, hits.

#include <embree3/rtcore.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

using namespace mitsuba;  // Mitsuba builds Embree inside its namespace

#ifdef EMBREE4
// Embree 4's C entry points that this harness calls (rtcore_device.h,
// rtcore_scene.h, rtcore_geometry.h, rtcore_buffer.h of Embree 4): the same
// signatures as Embree 3's but for the queries, which take an optional
// arguments struct instead of a context (null: the defaults, incoherent
// traversal, as Embree 3's default context). The ray and hit types are Embree
// 3's, which Embree 4 kept field for field; its hit may add `instPrimID` after
// `instID` (libraries built with instance arrays), which `PaddedRayHit` and
// `PaddedRayHit16` leave room for.
namespace embree4 {
extern "C" {
RTCDevice rtcNewDevice(const char *config);
void rtcReleaseDevice(RTCDevice device);
RTCScene rtcNewScene(RTCDevice device);
void rtcSetSceneBuildQuality(RTCScene scene, RTCBuildQuality quality);
void rtcSetSceneFlags(RTCScene scene, RTCSceneFlags flags);
void rtcCommitScene(RTCScene scene);
void rtcReleaseScene(RTCScene scene);
RTCGeometry rtcNewGeometry(RTCDevice device, RTCGeometryType type);
void *rtcSetNewGeometryBuffer(RTCGeometry geometry, RTCBufferType type, unsigned int slot, RTCFormat format,
                              size_t byte_stride, size_t item_count);
void rtcCommitGeometry(RTCGeometry geometry);
unsigned int rtcAttachGeometry(RTCScene scene, RTCGeometry geometry);
void rtcReleaseGeometry(RTCGeometry geometry);
void rtcIntersect1(RTCScene scene, RTCRayHit *rayhit, void *args);
void rtcOccluded1(RTCScene scene, RTCRay *ray, void *args);
void rtcIntersect16(const int *valid, RTCScene scene, RTCRayHit16 *rayhit, void *args);
void rtcOccluded16(const int *valid, RTCScene scene, RTCRay16 *ray, void *args);
}
}  // namespace embree4
namespace rtc = embree4;
#else
namespace rtc = mitsuba;
#endif

namespace {

double now() {
    using namespace std::chrono;
    return duration<double>(steady_clock::now().time_since_epoch()).count();
}

[[noreturn]] void fail(const std::string &msg) {
    std::fprintf(stderr, "embree_rays: %s\n", msg.c_str());
    std::exit(2);
}

/// The dump of benches/accel.rs (`GTRAYS1`): vertices, triangles, ray sets.
struct Dump {
    std::vector<char> bytes;
    size_t pos = 8;
    uint32_t u32() {
        if (pos + 4 > bytes.size()) fail("truncated dump");
        uint32_t v;
        std::memcpy(&v, bytes.data() + pos, 4);
        pos += 4;
        return v;
    }
    const char *take(size_t n) {
        if (pos + n > bytes.size()) fail("truncated dump");
        const char *p = bytes.data() + pos;
        pos += n;
        return p;
    }
};

struct Rays {
    std::vector<float> org, dir;  // xyz per ray
    size_t n = 0;
};

/// A ray and hit with room after them for the hit fields an Embree 4 library
/// may add (`instPrimID`, one per instance level: 4 bytes, 16 × 4 in a packet).
struct alignas(64) PaddedRayHit {
    RTCRayHit rh;
    unsigned int spare[16];
};
struct alignas(64) PaddedRayHit16 {
    RTCRayHit16 rh;
    unsigned int spare[16 * 4];
};

}  // namespace

int main(int argc, char **argv) {
    if (argc != 8) fail("usage: DUMP SET INTERSECT|OCCLUDED WIDTH NONE|ROBUST RUNS SECONDS");
    const std::string set = argv[2], query = argv[3], flags = argv[5];
    const int width = std::atoi(argv[4]), runs = std::atoi(argv[6]);
    const double seconds = std::atof(argv[7]);
    if (query != "INTERSECT" && query != "OCCLUDED") fail("query must be INTERSECT or OCCLUDED");
    if (width != 1 && width != 16) fail("width must be 1 or 16");
    if (flags != "NONE" && flags != "ROBUST") fail("scene flags must be NONE or ROBUST");
    const bool closest = query == "INTERSECT";

    Dump d;
    std::ifstream f(argv[1], std::ios::binary);
    if (!f) fail(std::string(argv[1]) + ": cannot read");
    d.bytes.assign(std::istreambuf_iterator<char>(f), {});
    if (d.bytes.size() < 8 || std::memcmp(d.bytes.data(), "GTRAYS1", 8) != 0)
        fail(std::string(argv[1]) + ": not a ray dump of benches/accel.rs");
    const uint32_t nv = d.u32(), nt = d.u32();
    const char *verts = d.take(12 * size_t(nv)), *tris = d.take(12 * size_t(nt));
    Rays rays;
    bool found = false;
    for (uint32_t s = 0, ns = d.u32(); s < ns; ++s) {
        const uint32_t len = d.u32();
        const std::string name(d.take(len), len);
        const uint32_t n = d.u32();
        d.u32();  // closest hits
        d.u32();  // any hits
        const char *o = d.take(12 * size_t(n)), *dir = d.take(12 * size_t(n));
        if (name == set) {
            rays.n = n;
            rays.org.assign(reinterpret_cast<const float *>(o), reinterpret_cast<const float *>(o) + 3 * n);
            rays.dir.assign(reinterpret_cast<const float *>(dir), reinterpret_cast<const float *>(dir) + 3 * n);
            found = true;
        }
    }
    if (!found) fail("no ray set " + set);

    RTCDevice device = rtc::rtcNewDevice("threads=1");
    if (!device) fail("rtcNewDevice failed");
    RTCScene scene = rtc::rtcNewScene(device);
    rtc::rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    rtc::rtcSetSceneFlags(scene, flags == "ROBUST" ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    RTCGeometry geom = rtc::rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    std::memcpy(rtc::rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, nv), verts, 12 * size_t(nv));
    std::memcpy(rtc::rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, nt), tris, 12 * size_t(nt));
    rtc::rtcCommitGeometry(geom);
    rtc::rtcAttachGeometry(scene, geom);
    rtc::rtcReleaseGeometry(geom);
    const double t_build = now();
    rtc::rtcCommitScene(scene);
    const double build_s = now() - t_build;

    const float *O = rays.org.data(), *D = rays.dir.data();
    const size_t n = rays.n;
    // One pass over the set; returns the hit count.
    auto pass = [&]() -> size_t {
#ifdef EMBREE4
        // Embree 4: a null arguments struct, its defaults.
        auto intersect1 = [&](RTCRayHit *rh) { rtc::rtcIntersect1(scene, rh, nullptr); };
        auto occluded1 = [&](RTCRay *r) { rtc::rtcOccluded1(scene, r, nullptr); };
        auto intersect16 = [&](const int *v, RTCRayHit16 *rh) { rtc::rtcIntersect16(v, scene, rh, nullptr); };
        auto occluded16 = [&](const int *v, RTCRay16 *r) { rtc::rtcOccluded16(v, scene, r, nullptr); };
#else
        RTCIntersectContext ctx;
        rtc::rtcInitIntersectContext(&ctx);
        auto intersect1 = [&](RTCRayHit *rh) { rtc::rtcIntersect1(scene, &ctx, rh); };
        auto occluded1 = [&](RTCRay *r) { rtc::rtcOccluded1(scene, &ctx, r); };
        auto intersect16 = [&](const int *v, RTCRayHit16 *rh) { rtc::rtcIntersect16(v, scene, &ctx, rh); };
        auto occluded16 = [&](const int *v, RTCRay16 *r) { rtc::rtcOccluded16(v, scene, &ctx, r); };
#endif
        size_t hits = 0;
        if (width == 1) {
            for (size_t i = 0; i < n; ++i) {
                PaddedRayHit p;
                RTCRayHit &rh = p.rh;
                RTCRay &r = rh.ray;
                r.org_x = O[3 * i], r.org_y = O[3 * i + 1], r.org_z = O[3 * i + 2], r.tnear = 0.f;
                r.dir_x = D[3 * i], r.dir_y = D[3 * i + 1], r.dir_z = D[3 * i + 2], r.time = 0.f;
                r.tfar = INFINITY, r.mask = ~0u, r.id = 0, r.flags = 0;
                if (closest) {
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    intersect1(&rh);
                    hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
                } else {
                    occluded1(&r);
                    hits += r.tfar < 0.f;  // Embree marks an occluded ray with tfar = -inf
                }
            }
            return hits;
        }
        PaddedRayHit16 p;
        alignas(64) int valid[16];
        RTCRayHit16 &rh = p.rh;
        RTCRay16 &r = rh.ray;
        for (size_t b = 0; b < n; b += 16) {
            for (size_t j = 0; j < 16; ++j) {
                const size_t i = std::min(b + j, n - 1);
                valid[j] = b + j < n ? -1 : 0;
                r.org_x[j] = O[3 * i], r.org_y[j] = O[3 * i + 1], r.org_z[j] = O[3 * i + 2], r.tnear[j] = 0.f;
                r.dir_x[j] = D[3 * i], r.dir_y[j] = D[3 * i + 1], r.dir_z[j] = D[3 * i + 2], r.time[j] = 0.f;
                r.tfar[j] = INFINITY, r.mask[j] = ~0u, r.id[j] = 0, r.flags[j] = 0;
                rh.hit.geomID[j] = RTC_INVALID_GEOMETRY_ID;
            }
            if (closest)
                intersect16(valid, &rh);
            else
                occluded16(valid, &r);
            for (size_t j = 0; j < 16; ++j)
                hits += valid[j] && (closest ? rh.hit.geomID[j] != RTC_INVALID_GEOMETRY_ID : r.tfar[j] < 0.f);
        }
        return hits;
    };

    double t0 = now();
    const size_t hits = pass();
    const double first_s = now() - t0;
    for (const double start = now(); now() - start < 1.0;) pass();
    std::vector<double> times;
    for (const double start = now(); int(times.size()) < runs || now() - start < seconds;) {
        t0 = now();
        if (pass() != hits) fail("a pass returned another hit count");
        times.push_back(now() - t0);
    }
    std::sort(times.begin(), times.end());
    const size_t m = times.size();
    const double median = m % 2 ? times[m / 2] : 0.5 * (times[m / 2 - 1] + times[m / 2]);
    std::printf("{\"median_s\": %.9g, \"first_s\": %.9g, \"build_s\": %.9g, \"hits\": %zu}\n", median, first_s, build_s, hits);
    rtc::rtcReleaseScene(scene);
    rtc::rtcReleaseDevice(device);
    return 0;
}
