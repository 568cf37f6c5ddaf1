/* ShadyLoc — loops shared between threads (core/WorkSharing.h). */
#include <shadyloc/core/WorkSharing.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <future>
#include <stdexcept>
#include <thread>
#include <vector>

using namespace shadyloc::core;

namespace
{
/** Spins until pred() or `seconds` passed; pred()'s last value. */
template <class P>
bool within(double seconds, P pred)
{
	const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
	while (!pred())
	{
		if (std::chrono::steady_clock::now() > end) return false;
		std::this_thread::yield();
	}
	return true;
}
}  // namespace

TEST(CoreWorkSharing, EveryLoopRunsEachItemOnceWhateverRunsIt)
{
	const size_t n = 1000;
	for (const ItemLoop& loop : {ItemLoop(runSerially), ItemLoop(runOnTwoThreads)})
	{
		std::vector<std::atomic<int>> ran(n);
		loop(n, [&](size_t i) { ran[i]++; });
		for (size_t i = 0; i < n; i++) ASSERT_EQ(ran[i].load(), 1) << "item " << i;
	}
}

TEST(CoreWorkSharing, AnIdleWorkerTakesItemsOfTheOthersLoop)
{
	// The owner's first item blocks until another item has run: only the
	// helper can run that one, so it is unblocked only if the helper took part.
	WorkSharing ws(2);
	const size_t n = 64;
	std::vector<std::atomic<int>> ran(n);
	std::atomic<int> done{0};
	const auto owner = std::this_thread::get_id();
	std::atomic<int> onHelper{0};
	auto helper = std::async(std::launch::async, [&] { ws.doneThenHelp(); });
	std::atomic<bool> unblocked{true}, ownerWaited{false};
	ws.run(n, [&](size_t i) {
		const bool mine = std::this_thread::get_id() == owner;
		if (mine && !ownerWaited.exchange(true)) unblocked = within(20.0, [&] { return done.load() >= 1; });
		if (!mine) onHelper++;
		ran[i]++;
		done++;
	});
	ws.doneThenHelp();
	helper.get();
	EXPECT_TRUE(unblocked) << "no item ran beside the owner's first within 20 s";
	EXPECT_GE(onHelper.load(), 1);
	EXPECT_EQ(ws.itemsHelped(), static_cast<size_t>(onHelper.load()));
	for (size_t i = 0; i < n; i++) ASSERT_EQ(ran[i].load(), 1) << "item " << i;
}

TEST(CoreWorkSharing, AHelpersFailureReachesTheOwnerAndNoWorkerHangs)
{
	WorkSharing ws(2);
	const auto owner = std::this_thread::get_id();
	std::atomic<int> done{0};
	std::atomic<bool> ownerWaited{false};
	auto helper = std::async(std::launch::async, [&] { ws.doneThenHelp(); });
	EXPECT_THROW(
		ws.run(
			64,
			[&](size_t) {
				// The owner's first item waits for the helper's first, which fails.
				const bool mine = std::this_thread::get_id() == owner;
				if (mine && !ownerWaited.exchange(true)) within(20.0, [&] { return done.load() >= 1; });
				if (!mine)
				{
					done++;
					throw std::runtime_error("resample failed");
				}
			}),
		std::runtime_error);
	ws.doneThenHelp();
	helper.get();  // returns: both workers are done
}

TEST(CoreWorkSharing, WorkersThatNeverPostStillEnd)
{
	WorkSharing ws(3);
	auto a = std::async(std::launch::async, [&] { ws.doneThenHelp(); });
	auto b = std::async(std::launch::async, [&] { ws.doneThenHelp(); });
	ws.run(5, [](size_t) {});
	ws.doneThenHelp();
	a.get();
	b.get();
	SUCCEED();
}
