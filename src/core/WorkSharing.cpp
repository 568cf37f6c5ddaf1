/* ShadyLoc — loops shared between threads (WorkSharing.h). */
#include <shadyloc/core/WorkSharing.h>

#include <atomic>
#include <exception>
#include <future>

namespace shadyloc::core
{
void runSerially(size_t n, const std::function<void(size_t)>& fn)
{
	for (size_t i = 0; i < n; i++) fn(i);
}

void runOnTwoThreads(size_t n, const std::function<void(size_t)>& fn)
{
	auto half = std::async(std::launch::async, [&] {
		for (size_t i = n / 2; i < n; i++) fn(i);
	});
	std::exception_ptr e;
	try
	{
		for (size_t i = 0; i < n / 2; i++) fn(i);
	}
	catch (...)
	{
		e = std::current_exception();
	}
	half.get();
	if (e) std::rethrow_exception(e);
}

struct WorkSharing::Job
{
	const std::function<void(size_t)>* fn = nullptr;
	size_t n = 0;
	std::atomic<size_t> next{0};
	int helpers = 0;  //!< helpers inside drain() (under the mutex)
	std::exception_ptr failure;	 //!< the first item's exception (under the mutex)
	std::mutex* mutex = nullptr;
};

size_t WorkSharing::drain(Job& job)
{
	size_t ran = 0;
	for (size_t i = job.next++; i < job.n; i = job.next++)
	{
		try
		{
			(*job.fn)(i);
		}
		catch (...)
		{
			std::lock_guard<std::mutex> lock(*job.mutex);
			if (!job.failure) job.failure = std::current_exception();
			job.next = job.n;  // stop the others too
		}
		ran++;
	}
	return ran;
}

void WorkSharing::run(size_t n, const std::function<void(size_t)>& fn)
{
	Job job;
	job.fn = &fn;
	job.n = n;
	job.mutex = &m_mutex;
	bool shared = false;
	{
		std::lock_guard<std::mutex> lock(m_mutex);
		if (!m_posted)	// a worker that finishes meanwhile joins in
		{
			m_posted = &job;
			shared = true;
		}
	}
	if (shared) m_changed.notify_all();
	drain(job);
	std::unique_lock<std::mutex> lock(m_mutex);
	if (shared)
	{
		m_posted = nullptr;	 // no helper enters any more; wait for those inside
		m_changed.wait(lock, [&] { return job.helpers == 0; });
	}
	if (job.failure) std::rethrow_exception(job.failure);
}

void WorkSharing::doneThenHelp()
{
	std::unique_lock<std::mutex> lock(m_mutex);
	m_working--;
	m_changed.notify_all();
	while (m_working > 0)
	{
		if (m_posted && m_posted->next < m_posted->n)
		{
			Job& job = *m_posted;
			job.helpers++;
			lock.unlock();
			const size_t ran = drain(job);
			lock.lock();
			m_helped += ran;
			job.helpers--;
			m_changed.notify_all();	 // the owner may be waiting for us
			continue;
		}
		m_changed.wait(lock);
	}
}

size_t WorkSharing::itemsHelped() const
{
	std::lock_guard<std::mutex> lock(m_mutex);
	return m_helped;
}

}  // namespace shadyloc::core
