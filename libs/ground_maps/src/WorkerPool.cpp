#include <gam/maps/WorkerPool.h>

namespace gam::maps
{
void WorkerPool::resize(int threads)
{
	threads = threads < 1 ? 1 : threads;
	if (threads == m_threads) return;
	stop();
	m_threads = threads;
}

void WorkerPool::stop()
{
	{
		std::lock_guard<std::mutex> lock(m_mutex);
		m_stopping = true;
	}
	m_wake.notify_all();
	for (std::thread& t : m_workers) t.join();
	m_workers.clear();
	m_stopping = false;
}

void WorkerPool::start()
{
	m_workers.reserve(size_t(m_threads - 1));
	for (int i = 1; i < m_threads; i++) m_workers.emplace_back([this] { workerLoop(); });
}

size_t WorkerPool::drain(Job job, void* context, size_t n)
{
	size_t ran = 0;
	for (size_t i = m_next.fetch_add(1); i < n; i = m_next.fetch_add(1), ran++) job(context, i);
	return ran;
}

void WorkerPool::run(size_t n, Job job, void* context)
{
	if (n == 0) return;
	if (m_threads == 1 || n == 1)
	{
		for (size_t i = 0; i < n; i++) job(context, i);
		return;
	}
	if (m_workers.empty()) start();
	{
		std::lock_guard<std::mutex> lock(m_mutex);
		m_job = job;
		m_context = context;
		m_count = n;
		m_finished = 0;
		m_next.store(0);
		m_generation++;
	}
	m_wake.notify_all();
	const size_t ran = drain(job, context, n);
	std::unique_lock<std::mutex> lock(m_mutex);
	m_finished += ran;
	// Every index done, and no worker still inside this run: a late one would
	// otherwise take an index of the next run with this run's job.
	m_done.wait(lock, [&] { return m_finished == m_count && m_busy == 0; });
}

void WorkerPool::workerLoop()
{
	uint64_t seen = 0;
	std::unique_lock<std::mutex> lock(m_mutex);
	while (true)
	{
		m_wake.wait(lock, [&] { return m_stopping || m_generation != seen; });
		if (m_stopping) return;
		seen = m_generation;
		const Job job = m_job;
		void* const context = m_context;
		const size_t n = m_count;
		m_busy++;
		lock.unlock();
		const size_t ran = drain(job, context, n);
		lock.lock();
		m_finished += ran;
		m_busy--;
		if (m_finished == m_count && m_busy == 0) m_done.notify_one();
	}
}

}  // namespace gam::maps
