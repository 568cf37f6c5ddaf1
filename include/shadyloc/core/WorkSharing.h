/* ShadyLoc — loops of independent items, run on one thread, on two, or
 * shared with a thread that has finished its own work.
 *
 * The combined system runs the monochrome and the invariant channels on two
 * threads, and one waits for the other at the end of every frame (about
 * 1-2 ms of the frame, TLocalisationUpdate::ms_wait): which channel finishes
 * first changes from frame to frame. WorkSharing lends the idle thread to
 * the loops the other still runs (the bootstrap's resamples), so the wait
 * shrinks without moving any work off its thread for good. An item writes
 * only its own result slot and the caller combines the slots in item order,
 * so the results are the same to the bit whoever ran which item.
 */
#pragma once

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <mutex>

namespace shadyloc::core
{
/** fn(i) for every i in [0, n), each exactly once, in any order and on any
 * thread; returns when all have run (rethrowing an item's exception). */
using ItemLoop = std::function<void(size_t n, const std::function<void(size_t)>& fn)>;

/** On the calling thread, in order. */
void runSerially(size_t n, const std::function<void(size_t)>& fn);
/** On the calling thread and one more (std::async), half each. */
void runOnTwoThreads(size_t n, const std::function<void(size_t)>& fn);

/** A set of `workers` threads that each run work of their own and, once
 * done, help with the loops the others have posted until every worker is
 * done. Made for one round (a frame); a new round needs a new object.
 *
 *   WorkSharing ws(2);
 *   thread A: ... ws.run(n, fn) ...; ws.doneThenHelp();
 *   thread B: ...;                   ws.doneThenHelp();
 */
class WorkSharing
{
   public:
	explicit WorkSharing(int workers) : m_working(workers) {}
	WorkSharing(const WorkSharing&) = delete;
	WorkSharing& operator=(const WorkSharing&) = delete;

	/** A worker's loop: run here, with idle workers taking items too. One
	 * loop is shared at a time; a second one meanwhile runs alone. */
	void run(size_t n, const std::function<void(size_t)>& fn);
	/** This worker's own work is done: it takes items of posted loops until
	 * every worker is done. Call it once per worker, also after a failure
	 * (else the others wait for it). */
	void doneThenHelp();
	/** run() as an ItemLoop (the object must outlive its use). */
	ItemLoop loop()
	{
		return [this](size_t n, const std::function<void(size_t)>& fn) { run(n, fn); };
	}
	/** Items that ran on a helper rather than on the loop's own thread. */
	size_t itemsHelped() const;

   private:
	struct Job;
	/** Takes and runs items of `job` until none is left; counts them. */
	static size_t drain(Job& job);

	mutable std::mutex m_mutex;
	std::condition_variable m_changed;	//!< a loop posted or finished, a worker done
	int m_working;	//!< workers not yet done with their own work
	Job* m_posted = nullptr;  //!< the loop open to helpers (the owner's stack)
	size_t m_helped = 0;
};

}  // namespace shadyloc::core
