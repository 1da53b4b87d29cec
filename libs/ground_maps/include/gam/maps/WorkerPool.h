// Ground-aware mapping for MRPT
// A small persistent pool of worker threads for the frames of several cameras
// (CGroundAwareOccupancyGrid::insertObservations, option `threads`). Its
// threads start on the first parallel run and then wait on a condition
// variable: no thread is created per frame, and a run allocates nothing.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <mutex>
#include <thread>
#include <vector>

namespace gam::maps
{
class WorkerPool
{
   public:
	using Job = void (*)(void* context, size_t index);

	/** `threads` counts the caller: threads - 1 workers (none for 1). */
	explicit WorkerPool(int threads = 1) : m_threads(threads < 1 ? 1 : threads) {}
	/** A copy has the same size and threads of its own (started when needed):
	 * threads are never shared between two owners. */
	WorkerPool(const WorkerPool& o) : WorkerPool(o.m_threads) {}
	WorkerPool& operator=(const WorkerPool& o)
	{
		if (this != &o) resize(o.m_threads);
		return *this;
	}
	~WorkerPool() { stop(); }

	int threads() const { return m_threads; }
	/** Stops the workers if the size changes; the new ones start on the next run(). */
	void resize(int threads);

	/** Calls job(context, i) once for every i in [0, n), on the workers and
	 * the calling thread, and returns when every call has returned. The jobs
	 * must not throw. Not reentrant: one run at a time per pool. */
	void run(size_t n, Job job, void* context);

   private:
	void stop();
	void start();
	void workerLoop();
	/** Takes indices until none is left; returns how many it ran. */
	size_t drain(Job job, void* context, size_t n);

	int m_threads;
	std::vector<std::thread> m_workers;
	std::mutex m_mutex;
	std::condition_variable m_wake, m_done;
	// The current run, guarded by m_mutex (m_next is taken without it).
	uint64_t m_generation = 0;
	bool m_stopping = false;
	Job m_job = nullptr;
	void* m_context = nullptr;
	size_t m_count = 0, m_finished = 0;
	int m_busy = 0;  // workers inside the current run: the next one waits for them
	std::atomic<size_t> m_next{0};
};

}  // namespace gam::maps
