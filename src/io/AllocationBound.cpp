/* ShadyLoc — per-thread allocation bound (see AllocationBound.h). */
#include <shadyloc/io/AllocationBound.h>

#include <opencv2/core.hpp>

#include <limits>
#include <mutex>

namespace shadyloc::io
{
namespace
{
struct TState
{
	AllocationBound::Check check = nullptr;
	void* context = nullptr;
	bool inCheck = false;  //!< the check's own allocations pass
	size_t lastRefused = 0;
};
thread_local TState t_state;

/** cv::Mat's allocator with the bound in front; otherwise the one it replaced. */
class BoundedMatAllocator : public cv::MatAllocator
{
   public:
	explicit BoundedMatAllocator(cv::MatAllocator* next) : m_next(next) {}
	cv::UMatData* allocate(
		int dims, const int* sizes, int type, void* data, size_t* step, cv::AccessFlag flags,
		cv::UMatUsageFlags usageFlags) const override
	{
		if (!data)
		{
			size_t total = CV_ELEM_SIZE(type);
			for (int i = 0; i < dims; i++)
			{
				const size_t s = sizes[i] > 0 ? static_cast<size_t>(sizes[i]) : 0;
				total = (s != 0 && total > std::numeric_limits<size_t>::max() / s) ? std::numeric_limits<size_t>::max()
																				   : total * s;
			}
			if (!AllocationBound::allowed(total))
				CV_Error_(cv::Error::StsNoMem, ("image of %zu bytes exceeds what the stream holds", total));
		}
		return m_next->allocate(dims, sizes, type, data, step, flags, usageFlags);
	}
	bool allocate(cv::UMatData* data, cv::AccessFlag accessflags, cv::UMatUsageFlags usageFlags) const override
	{
		return m_next->allocate(data, accessflags, usageFlags);
	}
	void deallocate(cv::UMatData* data) const override { m_next->deallocate(data); }

   private:
	cv::MatAllocator* m_next;
};

void installMatAllocator()
{
	static std::once_flag once;
	std::call_once(once, [] {
		static BoundedMatAllocator a(cv::Mat::getDefaultAllocator());
		cv::Mat::setDefaultAllocator(&a);
	});
}
}  // namespace

AllocationBound::AllocationBound(Check check, void* context)
	: m_prevCheck(t_state.check), m_prevContext(t_state.context)
{
	installMatAllocator();
	t_state.check = check;
	t_state.context = context;
	t_state.lastRefused = 0;
}

AllocationBound::~AllocationBound()
{
	t_state.check = m_prevCheck;
	t_state.context = m_prevContext;
}

bool AllocationBound::allowed(size_t bytes) noexcept
{
	TState& s = t_state;
	if (!s.check || s.inCheck || bytes <= kAlwaysAllowed) return true;
	s.inCheck = true;
	bool ok = false;
	try
	{
		ok = s.check(bytes, s.context);
	}
	catch (...)
	{
		ok = false;
	}
	s.inCheck = false;
	if (!ok) s.lastRefused = bytes;
	return ok;
}

size_t AllocationBound::lastRefused() noexcept { return t_state.lastRefused; }

AllocationBound::Pause::Pause() : m_prev(t_state.inCheck) { t_state.inCheck = true; }
AllocationBound::Pause::~Pause() { t_state.inCheck = m_prev; }

}  // namespace shadyloc::io
