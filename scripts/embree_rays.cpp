// Embree's own ray throughput on the `accel` bench's dumped rays, called from
// C++ with no binding in between: the configurations a C++ renderer would
// use, for scripts/bench_embree.py.
//
//   embree_rays DUMP SET INTERSECT|OCCLUDED WIDTH NONE|ROBUST RUNS SECONDS
//
// Builds against the Embree 3 that Mitsuba 3's wheel ships (its headers and
// libembree3.so, in Mitsuba's namespace), with Mitsuba's scene settings
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

    RTCDevice device = rtcNewDevice("threads=1");
    if (!device) fail("rtcNewDevice failed");
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    rtcSetSceneFlags(scene, flags == "ROBUST" ? RTC_SCENE_FLAG_ROBUST : RTC_SCENE_FLAG_NONE);
    RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    std::memcpy(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 12, nv), verts, 12 * size_t(nv));
    std::memcpy(rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, nt), tris, 12 * size_t(nt));
    rtcCommitGeometry(geom);
    rtcAttachGeometry(scene, geom);
    rtcReleaseGeometry(geom);
    const double t_build = now();
    rtcCommitScene(scene);
    const double build_s = now() - t_build;

    const float *O = rays.org.data(), *D = rays.dir.data();
    const size_t n = rays.n;
    // One pass over the set; returns the hit count.
    auto pass = [&]() -> size_t {
        RTCIntersectContext ctx;
        rtcInitIntersectContext(&ctx);
        size_t hits = 0;
        if (width == 1) {
            for (size_t i = 0; i < n; ++i) {
                RTCRayHit rh;
                RTCRay &r = rh.ray;
                r.org_x = O[3 * i], r.org_y = O[3 * i + 1], r.org_z = O[3 * i + 2], r.tnear = 0.f;
                r.dir_x = D[3 * i], r.dir_y = D[3 * i + 1], r.dir_z = D[3 * i + 2], r.time = 0.f;
                r.tfar = INFINITY, r.mask = ~0u, r.id = 0, r.flags = 0;
                if (closest) {
                    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                    rtcIntersect1(scene, &ctx, &rh);
                    hits += rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
                } else {
                    rtcOccluded1(scene, &ctx, &r);
                    hits += r.tfar < 0.f;  // Embree marks an occluded ray with tfar = -inf
                }
            }
            return hits;
        }
        alignas(64) RTCRayHit16 rh;
        alignas(64) int valid[16];
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
                rtcIntersect16(valid, scene, &ctx, &rh);
            else
                rtcOccluded16(valid, scene, &ctx, &r);
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
    rtcReleaseScene(scene);
    rtcReleaseDevice(device);
    return 0;
}
