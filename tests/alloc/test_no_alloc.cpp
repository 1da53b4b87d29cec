// Issue #6 "Real time": no heap allocation per depth frame in steady state.
//
// This executable replaces the global operator new / delete (every variant:
// plain, array, nothrow, aligned, sized) and the C allocator (malloc, calloc,
// realloc, memalign, aligned_alloc, posix_memalign) with versions that count
// the allocations made by the current thread while an AllocCounter is alive.
// After a few warm-up frames (scratch buffers reach their final capacity),
// further frames must allocate nothing.
//
// Set GAM_ALLOC_TRACE=1 to print a backtrace of every counted allocation
// (link with -rdynamic, as tests/CMakeLists.txt does, for readable names).
#include <execinfo.h>
#include <gtest/gtest.h>
#include <mrpt/maps/CGroundAwareOccupancyGrid.h>
#include <mrpt/obs/CObservation3DRangeScan.h>
#include <mrpt/obs/CRawlog.h>
#include <mrpt/system/filesystem.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <random>

#include "../maps/real_data.h"
#include "../maps/synthetic_scene.h"
#include "gam/core/ElevationGrid.h"
#include "gam/core/GroundAwarePipeline.h"

// ---------------------------------------------------------------------------
// Counting allocator.
// glibc's allocator under its internal names: the replacements below forward
// to it, so memory from any entry point may be freed by any other.
extern "C"
{
	void* __libc_malloc(std::size_t);
	void* __libc_calloc(std::size_t, std::size_t);
	void* __libc_realloc(void*, std::size_t);
	void* __libc_memalign(std::size_t, std::size_t);
	void __libc_free(void*);
}

namespace
{
std::atomic<size_t> g_allocs{0};
thread_local bool t_counting = false;
// Counts every thread's allocations (the worker threads of `threads` > 1).
std::atomic<bool> g_countAllThreads{false};
thread_local bool t_inTrace = false;
bool g_trace = false;

void noteAllocation(std::size_t n)
{
	if (!t_counting && !g_countAllThreads.load(std::memory_order_relaxed)) return;
	g_allocs.fetch_add(1, std::memory_order_relaxed);
	if (g_trace && !t_inTrace)
	{
		t_inTrace = true;
		char head[64];
		const int len = std::snprintf(head, sizeof head, "--- allocation of %zu bytes:\n", n);
		if (len > 0) (void)!write(2, head, size_t(len));
		void* frames[40];
		const int k = backtrace(frames, 40);
		backtrace_symbols_fd(frames, k, 2);
		t_inTrace = false;
	}
}

void* allocOrThrow(std::size_t n)
{
	noteAllocation(n);
	if (void* p = __libc_malloc(n ? n : 1)) return p;
	throw std::bad_alloc();
}
void* allocNoThrow(std::size_t n) noexcept
{
	noteAllocation(n);
	return __libc_malloc(n ? n : 1);
}
void* alignedAlloc(std::size_t n, std::size_t al) noexcept
{
	noteAllocation(n);
	return __libc_memalign(std::max(al, sizeof(void*)), n ? n : 1);
}
void* alignedAllocOrThrow(std::size_t n, std::align_val_t al)
{
	if (void* p = alignedAlloc(n, std::size_t(al))) return p;
	throw std::bad_alloc();
}

/** Counts this thread's operator-new calls during its lifetime. */
class AllocCounter
{
   public:
	AllocCounter() : m_start(g_allocs.load()) { t_counting = true; }
	~AllocCounter() { t_counting = false; }
	size_t count() const { return g_allocs.load() - m_start; }

   private:
	size_t m_start;
};

/** Counts the allocations of every thread during its lifetime. */
class AllThreadsAllocCounter
{
   public:
	AllThreadsAllocCounter() : m_start(g_allocs.load()) { g_countAllThreads = true; }
	~AllThreadsAllocCounter() { g_countAllThreads = false; }
	size_t count() const { return g_allocs.load() - m_start; }

   private:
	size_t m_start;
};
}  // namespace

void* operator new(std::size_t n) { return allocOrThrow(n); }
void* operator new[](std::size_t n) { return allocOrThrow(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { return allocNoThrow(n); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { return allocNoThrow(n); }
void* operator new(std::size_t n, std::align_val_t a) { return alignedAllocOrThrow(n, a); }
void* operator new[](std::size_t n, std::align_val_t a) { return alignedAllocOrThrow(n, a); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept
{
	return alignedAlloc(n, std::size_t(a));
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept
{
	return alignedAlloc(n, std::size_t(a));
}

void operator delete(void* p) noexcept { __libc_free(p); }
void operator delete[](void* p) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t) noexcept { __libc_free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { __libc_free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { __libc_free(p); }
void operator delete(void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { __libc_free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { __libc_free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { __libc_free(p); }

// C allocations count too (nanoflann's PooledAllocator, Eigen's aligned
// malloc, C libraries): glibc lets a program replace these.
extern "C"
{
	void* malloc(std::size_t n)
	{
		noteAllocation(n);
		return __libc_malloc(n);
	}
	void* calloc(std::size_t k, std::size_t n)
	{
		noteAllocation(k * n);
		return __libc_calloc(k, n);
	}
	void* realloc(void* p, std::size_t n)
	{
		noteAllocation(n);
		return __libc_realloc(p, n);
	}
	void free(void* p) { __libc_free(p); }
	void* memalign(std::size_t a, std::size_t n)
	{
		noteAllocation(n);
		return __libc_memalign(a, n);
	}
	void* aligned_alloc(std::size_t a, std::size_t n)
	{
		noteAllocation(n);
		return __libc_memalign(a, n);
	}
	int posix_memalign(void** out, std::size_t a, std::size_t n)
	{
		if (a < sizeof(void*) || (a & (a - 1)) != 0) return EINVAL;
		noteAllocation(n);
		void* p = __libc_memalign(a, n);
		if (!p) return ENOMEM;
		*out = p;
		return 0;
	}
}

// ---------------------------------------------------------------------------
using mrpt::DEG2RAD;
using mrpt::maps::CGroundAwareOccupancyGrid;
using mrpt::obs::CObservation3DRangeScan;
using mrpt::poses::CPose3D;

namespace
{
constexpr int kWarmUp = 5;
constexpr int kMeasured = 20;

struct TraceSetup
{
	TraceSetup()
	{
		g_trace = std::getenv("GAM_ALLOC_TRACE") != nullptr;
		// backtrace() loads libgcc on its first call: do it outside any count.
		void* f[2];
		backtrace(f, 2);
	}
} g_traceSetup;

using testdata::firstScan;
using testdata::realData;

// Floor with a 10 cm box and a hole, seen by a Kinect 1 m up pitched 25 deg
// down: ground, obstacle, drop and drop-ray evidence, like tests/maps.
CObservation3DRangeScan::Ptr syntheticFrame()
{
	auto s = testscene::floorWithHole(-1, 6, -3, 3, 2.0, 2.4, -0.3, 0.3, 0.5);
	s.push_back({1.5, 0.6, 0.0, 1.7, 0.8, 0.10});
	return testscene::renderDepth(s, CPose3D(0, 0, 1.0, 0, DEG2RAD(25.0), 0));
}

/** Inserts `frames` round-robin, the robot moving 1 cm along x (and turning a
 * little) each time, so the 2.5D frame grid recenters on it. Returns the
 * largest number of allocations of one measured insertion. */
size_t maxAllocsPerFrame(
	CGroundAwareOccupancyGrid& grid, const std::vector<CObservation3DRangeScan::Ptr>& frames, size_t& total)
{
	int step = 0;
	auto poseAt = [](int k) { return CPose3D(0.01 * k, 0.003 * k, 0, DEG2RAD(0.2 * k), 0, 0); };
	for (int i = 0; i < kWarmUp; i++)
		for (const auto& f : frames)
		{
			grid.insertObservation(*f, poseAt(step++));
			EXPECT_TRUE(grid.lastFrame().detection.ok()) << grid.lastFrame().detection.describe();
		}
	size_t worst = 0;
	total = 0;
	for (int i = 0; i < kMeasured; i++)
		for (const auto& f : frames)
		{
			const CPose3D pose = poseAt(step++);
			size_t n;
			{
				AllocCounter count;
				grid.insertObservation(*f, pose);
				n = count.count();
			}
			EXPECT_TRUE(grid.lastFrame().detection.ok()) << grid.lastFrame().detection.describe();
			EXPECT_TRUE(grid.lastFrame().ism.applied);
			total += n;
			worst = std::max(worst, n);
		}
	return worst;
}
}  // namespace

TEST(NoAlloc, CounterSeesAllocations)
{
	// The test must be able to fail: an allocation inside the scope is counted.
	AllocCounter count;
	auto* v = new std::vector<int>(100);
	delete v;
	EXPECT_EQ(count.count(), 2u);
	// So is a C allocation (volatile: the compiler may not elide it).
	void* volatile p = std::malloc(64);
	std::free(p);
	EXPECT_EQ(count.count(), 3u);
}

TEST(NoAlloc, GroundAwareGridSyntheticFrameSteadyState)
{
	CGroundAwareOccupancyGrid grid;
	std::vector<CObservation3DRangeScan::Ptr> frames{syntheticFrame()};
	size_t total = 0;
	const size_t worst = maxAllocsPerFrame(grid, frames, total);
	std::cout << "[alloc] synthetic: " << total << " allocations in " << kMeasured << " frames (worst frame " << worst
			  << ")\n";
	EXPECT_EQ(worst, 0u) << "heap allocations per frame after warm-up; run with GAM_ALLOC_TRACE=1 to see where";
}

TEST(NoAlloc, GroundAwareGridDecimatedFrameSteadyState)
{
	// decimation = 2: the decimated frame and its ray table are built on the
	// first frame and reused (the flying-pixel filter runs on that frame).
	CGroundAwareOccupancyGrid grid;
	auto o = grid.groundOptions();
	o.pipeline.projection.decimation = 2;
	grid.setGroundOptions(o);
	std::vector<CObservation3DRangeScan::Ptr> frames{syntheticFrame()};
	size_t total = 0;
	const size_t worst = maxAllocsPerFrame(grid, frames, total);
	std::cout << "[alloc] synthetic, decimation 2: " << total << " allocations in " << kMeasured
			  << " frames (worst frame " << worst << ")\n";
	EXPECT_EQ(worst, 0u) << "heap allocations per frame after warm-up; run with GAM_ALLOC_TRACE=1 to see where";
}

TEST(NoAlloc, GroundAwareGridRealAndSyntheticFramesSteadyState)
{
	auto real = firstScan("mrpt_3d_obs_ground/test-3d-obs-ground.rawlog");
	if (!real) GTEST_SKIP() << "real data not found: " << realData("mrpt_3d_obs_ground/test-3d-obs-ground.rawlog");
	CGroundAwareOccupancyGrid grid;
	// Two different frames alternating: buffers must hold the larger of both.
	std::vector<CObservation3DRangeScan::Ptr> frames{real, syntheticFrame()};
	size_t total = 0;
	const size_t worst = maxAllocsPerFrame(grid, frames, total);
	std::cout << "[alloc] real+synthetic: " << total << " allocations in " << kMeasured * frames.size()
			  << " frames (worst frame " << worst << ")\n";
	EXPECT_EQ(worst, 0u) << "heap allocations per frame after warm-up; run with GAM_ALLOC_TRACE=1 to see where";
}

// Issue #28: two cameras at one pose through insertObservations(), with
// threads = 1 and 2 (the worker's allocations count too): nothing either way
// once the pool's thread and each camera's pipeline exist.
TEST(NoAlloc, TwoCamerasInsertObservationsThreads1And2SteadyState)
{
	auto s = testscene::floorWithHole(-1, 6, -3, 3, 2.0, 2.4, -0.3, 0.3, 0.5);
	s.push_back({1.5, 0.6, 0.0, 1.7, 0.8, 0.10});
	auto forward = testscene::renderDepth(s, CPose3D(0.10, 0, 0.80, 0, DEG2RAD(25.0), 0));
	auto down = testscene::renderDepth(s, CPose3D(0.05, 0, 0.60, 0, DEG2RAD(60.0), 0));
	down->sensorLabel = "KINECT_DOWN";
	const std::vector<const mrpt::obs::CObservation*> set{forward.get(), down.get()};
	for (const int threads : {1, 2})
	{
		CGroundAwareOccupancyGrid grid;
		auto o = grid.groundOptions();
		o.threads = threads;
		grid.setGroundOptions(o);
		auto poseAt = [](int k) { return CPose3D(0.01 * k, 0.003 * k, 0, DEG2RAD(0.2 * k), 0, 0); };
		int step = 0;
		for (int i = 0; i < kWarmUp; i++) grid.insertObservations(set, poseAt(step++));
		size_t worst = 0, total = 0;
		for (int i = 0; i < kMeasured; i++)
		{
			const CPose3D pose = poseAt(step++);
			size_t n;
			{
				AllThreadsAllocCounter count;
				grid.insertObservations(set, pose);
				n = count.count();
			}
			EXPECT_TRUE(grid.lastFrame().detection.ok()) << grid.lastFrame().detection.describe();
			total += n;
			worst = std::max(worst, n);
		}
		if (threads > 1)
		{
			EXPECT_GT(grid.parallelStats().ran_ahead, 0u);
		}
		std::cout << "[alloc] two cameras, threads=" << threads << ": " << total << " allocations in " << kMeasured
				  << " frame pairs (worst pair " << worst << ")\n";
		EXPECT_EQ(worst, 0u) << "threads=" << threads
							 << ": heap allocations per frame pair after warm-up; GAM_ALLOC_TRACE=1 shows where";
	}
}

// The pure core pipeline (no MRPT): gam::GroundAwarePipeline, the object the
// map runs: 2.5D map, 3-sigma filter, IDW, RRT-GPD, ISM.
TEST(NoAlloc, CorePipelineSteadyState)
{
	gam::GroundAwarePipeline pipeline;  // m_x = m_y = 200 at 5 cm, IDW radius 1

	// A noisy floor with a 15 cm box and a gentle ramp, in a fixed point set
	// (map frame: the sensor transform is the identity).
	std::mt19937 rng(7);
	std::normal_distribution<float> noise(0.f, 0.004f);
	std::uniform_real_distribution<double> U(0.0, 1.0);
	std::vector<float> xs, ys, zs;
	for (int i = 0; i < 60000; i++)
	{
		const double x = 0.3 + 3.5 * U(rng), y = -2.0 + 4.0 * U(rng);
		float z = noise(rng);
		if (x > 1.5 && x < 1.8 && y > 0.3 && y < 0.6) z += 0.15f;
		if (x > 2.5 && y < -0.5) z += float(0.1 * (x - 2.5));  // ~5.7 deg ramp
		xs.push_back(float(x));
		ys.push_back(float(y));
		zs.push_back(z);
	}
	gam::SensorFrame frame;
	frame.x = xs.data();
	frame.y = ys.data();
	frame.z = zs.data();
	frame.point_count = xs.size();

	size_t worst = 0;
	for (int k = 0; k < kWarmUp + kMeasured; k++)
	{
		const double rx = 0.01 * k;  // robot moves 1 cm per frame: the frame grid recentres
		frame.sensor_position = Eigen::Vector3d(rx, 0, 1.0);
		size_t n;
		const gam::FrameResult* r;
		{
			AllocCounter count;
			r = &pipeline.process(frame, Eigen::Vector3d(rx, 0, 0), gam::GridLattice{0, 0, 0.05});
			n = count.count();
		}
		ASSERT_TRUE(r->detection.ok()) << r->detection.describe();
		ASSERT_TRUE(r->ism.applied);
		if (k >= kWarmUp)
			worst = std::max(worst, n);
		else if (k == 0)
			std::cout << "[alloc] core: first frame " << n << " allocations\n";
	}
	std::cout << "[alloc] core: worst steady-state frame " << worst << " allocations\n";
	EXPECT_EQ(worst, 0u) << "heap allocations per frame after warm-up; run with GAM_ALLOC_TRACE=1 to see where";
}

// The reused scratch must follow a change of grid size (a smaller grid after a
// larger one wrote past the end of the node mask before; ASan builds see it).
TEST(NoAlloc, DetectorReusesScratchAcrossGridSizes)
{
	gam::RrtGroundDetector rrt;
	gam::GroundDetection det;
	for (int n : {200, 60, 200, 40})
	{
		gam::GridGeometry geom;
		geom.nx = geom.ny = n;
		geom.x_min = geom.y_min = -0.5 * n * geom.resolution;
		gam::ElevationGrid grid(geom);
		gam::BinnedPoints bins;
		std::mt19937 rng(3);
		std::normal_distribution<float> noise(0.f, 0.003f);
		for (int iy = 0; iy < n; iy++)
			for (int ix = 0; ix < n; ix++)
				for (int k = 0; k < 4; k++) bins.push(uint32_t(geom.index(ix, iy)), noise(rng));
		grid.insert(bins, gam::OutlierFilterParams{});
		rrt.detect(grid, gam::GroundSeedHint{}, det);
		ASSERT_TRUE(det.ok()) << n << ": " << det.describe();
		for (const auto& node : det.nodes) EXPECT_TRUE(grid.geometry().inside(geom.ix(node.x), geom.iy(node.y)));
	}
}
