/* ShadyLoc — the global operator new/delete, replaced so that an active
 * io::AllocationBound sees every large allocation of its thread (strings and
 * vectors that MRPT sizes from length fields). Without an active bound they
 * behave exactly as the standard ones: malloc/free, std::bad_alloc on failure.
 *
 * Defined in the library (which programs linking it pick up, as they come
 * before libstdc++ in symbol lookup); sanitizer builds, whose runtime brings
 * its own operator new, compile this file into their executables as well. */
#include <shadyloc/io/AllocationBound.h>

#include <cstdlib>
#include <new>

namespace
{
void* allocate(std::size_t n)
{
	if (!shadyloc::io::AllocationBound::allowed(n)) throw std::bad_alloc();
	for (;;)
	{
		if (void* p = std::malloc(n ? n : 1)) return p;
		std::new_handler h = std::get_new_handler();
		if (!h) throw std::bad_alloc();
		h();
	}
}
void* allocateAligned(std::size_t n, std::align_val_t al)
{
	if (!shadyloc::io::AllocationBound::allowed(n)) throw std::bad_alloc();
	std::size_t a = static_cast<std::size_t>(al);
	if (a < sizeof(void*)) a = sizeof(void*);
	for (;;)
	{
		void* p = nullptr;
		if (posix_memalign(&p, a, n ? n : 1) == 0) return p;
		std::new_handler h = std::get_new_handler();
		if (!h) throw std::bad_alloc();
		h();
	}
}
}  // namespace

void* operator new(std::size_t n) { return allocate(n); }
void* operator new[](std::size_t n) { return allocate(n); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept
{
	try
	{
		return allocate(n);
	}
	catch (...)
	{
		return nullptr;
	}
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept
{
	try
	{
		return allocate(n);
	}
	catch (...)
	{
		return nullptr;
	}
}
void* operator new(std::size_t n, std::align_val_t a) { return allocateAligned(n, a); }
void* operator new[](std::size_t n, std::align_val_t a) { return allocateAligned(n, a); }
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept
{
	try
	{
		return allocateAligned(n, a);
	}
	catch (...)
	{
		return nullptr;
	}
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept
{
	try
	{
		return allocateAligned(n, a);
	}
	catch (...)
	{
		return nullptr;
	}
}

void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { std::free(p); }
