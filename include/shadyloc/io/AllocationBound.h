/* ShadyLoc — a per-thread bound on single memory allocations.
 *
 * MRPT's deserialisation allocates from length fields before it reads the
 * bytes they announce (a string, a vector, a cv::Mat for an image): a single
 * flipped byte can ask for gigabytes. While an AllocationBound is alive on a
 * thread, every allocation larger than kAlwaysAllowed made there (through
 * operator new, which this library replaces, or cv::Mat) is first put to
 * the bound's check; a refused allocation throws std::bad_alloc (operator
 * new) or cv::Exception (cv::Mat) instead of reserving the memory.
 *
 * The check of RawlogReader allows an allocation only if at least that many
 * bytes remain in the stream. Other threads are never affected; raw
 * malloc()/realloc() calls inside MRPT are not seen (see docs/hardening.md).
 */
#pragma once

#include <cstddef>

namespace shadyloc::io
{
class AllocationBound
{
   public:
	/** Returns true if an allocation of `bytes` may go ahead. It may itself
	 * allocate (nested allocations are not checked). */
	using Check = bool (*)(size_t bytes, void* context);

	/** Smaller allocations are never checked [bytes]. */
	static constexpr size_t kAlwaysAllowed = 256 * 1024;

	AllocationBound(Check check, void* context);
	~AllocationBound();
	AllocationBound(const AllocationBound&) = delete;
	AllocationBound& operator=(const AllocationBound&) = delete;

	/** Whether the current thread may allocate `bytes` now (true when no
	 * bound is active). Used by the replaced operator new and cv::Mat. */
	static bool allowed(size_t bytes) noexcept;

	/** The size of the last refused allocation on this thread (0: none). */
	static size_t lastRefused() noexcept;

	/** While alive, this thread's allocations are not checked (for the
	 * reader's own buffers, which grow only as far as the data goes). */
	class Pause
	{
	   public:
		Pause();
		~Pause();
		Pause(const Pause&) = delete;
		Pause& operator=(const Pause&) = delete;

	   private:
		bool m_prev;
	};

   private:
	Check m_prevCheck;
	void* m_prevContext;
};

}  // namespace shadyloc::io
