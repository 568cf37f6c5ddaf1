/* ShadyLoc — outputs committed together (see OutputTransaction.h). */
#include <shadyloc/io/OutputTransaction.h>

#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <regex>
#include <set>
#include <stdexcept>
#include <system_error>
#include <thread>

#include <pthread.h>
#include <sys/stat.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace shadyloc::io
{
namespace
{
// ---------------------------------------------------------------- registry
std::recursive_mutex& registryMutex()
{
	static std::recursive_mutex m;
	return m;
}
std::set<std::string>& registry()
{
	static std::set<std::string> r;
	return r;
}

size_t removeRegisteredTemporaries()
{
	std::lock_guard<std::recursive_mutex> lock(registryMutex());
	size_t n = 0;
	for (const auto& p : registry())
	{
		// A writer may still add files to a folder being removed: retry.
		for (int attempt = 0; attempt < 5; attempt++)
		{
			std::error_code ec;
			const auto removed = fs::remove_all(p, ec);
			if (!ec)
			{
				n += removed > 0;
				break;
			}
		}
	}
	registry().clear();
	return n;
}

std::string suffixFor(const char* kind) { return std::string(".") + kind + "-" + std::to_string(::getpid()); }

/** "dir/.<stem><.kind-pid><ext>" for a file, "dir/.<name><.kind-pid>" for a directory. */
std::string siblingFor(const std::string& path, const char* kind, bool dir)
{
	const fs::path p(path);
	const std::string name = dir ? p.filename().string() : p.stem().string();
	const std::string ext = dir ? std::string() : p.extension().string();
	return (p.parent_path() / ("." + name + suffixFor(kind) + ext)).string();
}

std::string canonicalOf(const std::string& path)
{
	std::error_code ec;
	fs::path c = fs::weakly_canonical(fs::absolute(path), ec);
	if (ec) c = fs::absolute(path).lexically_normal();
	std::string s = c.string();
	while (s.size() > 1 && s.back() == '/') s.pop_back();
	return s;
}

/** True if `inner` lies strictly inside the directory `outer` (canonical paths). */
bool isInside(const std::string& inner, const std::string& outer)
{
	if (inner.size() <= outer.size() || inner.compare(0, outer.size(), outer) != 0) return false;
	return outer == "/" || inner[outer.size()] == '/';
}

bool alive(long pid)
{
	if (pid <= 0) return false;
	if (pid == ::getpid()) return true;
	return ::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM;
}
}  // namespace

void registerTemporary(const std::string& path)
{
	std::lock_guard<std::recursive_mutex> lock(registryMutex());
	registry().insert(path);
}

void unregisterTemporary(const std::string& path)
{
	std::lock_guard<std::recursive_mutex> lock(registryMutex());
	registry().erase(path);
}

void installSignalCleanup()
{
	static std::once_flag once;
	std::call_once(once, [] {
		sigset_t set;
		sigemptyset(&set);
		for (int s : {SIGINT, SIGTERM, SIGHUP, SIGQUIT}) sigaddset(&set, s);
		// Blocked here, so in every thread started later; only the thread
		// below takes them (sigwait), outside any signal handler.
		pthread_sigmask(SIG_BLOCK, &set, nullptr);
		std::thread([set] {
			int sig = 0;
			while (sigwait(&set, &sig) != 0)
			{
			}
			// Other threads run on while this one cleans up: one may create a
			// temporary it registered just before (a file opened, a folder made)
			// after the first pass. The registry stays locked, so nothing new is
			// registered; two later passes take what was still being created.
			std::unique_lock<std::recursive_mutex> hold(registryMutex());
			std::set<std::string> all = registry();
			size_t n = removeRegisteredTemporaries();
			for (const int waitMs : {50, 100})
			{
				std::this_thread::sleep_for(std::chrono::milliseconds(waitMs));
				for (const auto& p : all)
				{
					std::error_code ec;
					fs::remove_all(p, ec);
				}
			}
			char msg[160];
			const int len = std::snprintf(
				msg, sizeof(msg), "\nshadyloc: interrupted by signal %d (%s); %zu temporary output(s) removed\n", sig,
				strsignal(sig), n);
			if (len > 0) [[maybe_unused]] auto w = ::write(2, msg, static_cast<size_t>(len));
			// End as the signal would have (exit status 128 + sig in a shell).
			std::signal(sig, SIG_DFL);
			sigset_t one;
			sigemptyset(&one);
			sigaddset(&one, sig);
			pthread_sigmask(SIG_UNBLOCK, &one, nullptr);
			std::raise(sig);
			::_exit(128 + sig);
		}).detach();
	});
}

std::string temporaryPathFor(const std::string& path) { return siblingFor(path, "tmp", false); }

const char* const kOutputMarker = ".shadyloc-output";

namespace
{
/** The kind named by the marker in `dir`, "" if it has none. */
std::string markedKind(const fs::path& dir)
{
	std::ifstream f(dir / kOutputMarker);
	std::string kind;
	std::getline(f, kind);
	return kind;
}
}  // namespace

void checkReplaceableFolder(const std::string& path, const std::string& what, const std::string& kind)
{
	std::error_code ec;
	if (!fs::is_directory(path, ec) || fs::is_empty(path, ec)) return;
	// Only a folder known to be our own earlier output may go: anything else
	// (the user's files, the command's inputs, another command's output)
	// would be lost without a trace.
	const std::string found = markedKind(path);
	if (found == kind) return;
	throw std::invalid_argument(
		what + " '" + path + "': the folder exists and is not an earlier " + kind + " (" +
		(found.empty() ? std::string("no '") + kOutputMarker + "' file in it" : "it is a " + found) +
		"); it would be replaced as a whole: nothing was changed; remove it or choose another folder");
}

void markOutputFolder(const std::string& dir, const std::string& kind)
{
	std::ofstream f(fs::path(dir) / kOutputMarker);
	f << kind << "\n";
	if (!f) throw std::runtime_error("cannot write '" + (fs::path(dir) / kOutputMarker).string() + "'");
}

std::vector<std::string> staleTemporaries(const std::string& dir)
{
	// Ours: ".<name>.tmp-<pid>[.ext]" and ".<name>.old-<pid>[.ext]"; older
	// versions: ".<name>.tmp", ".<stem>.tmp.<ext>", "<stem>_Images.tmp".
	static const std::regex withPid(R"(^\..+\.(tmp|old)-([0-9]+)(\.[^.]*)?$)");
	static const std::regex legacy(R"(^(\..+\.tmp(\.[^.]+)?|.+_Images\.tmp)$)");
	std::vector<std::string> out;
	std::error_code ec;
	const fs::path d = dir.empty() ? fs::path(".") : fs::path(dir);
	for (fs::directory_iterator it(d, ec), end; !ec && it != end; it.increment(ec))
	{
		const std::string name = it->path().filename().string();
		std::smatch m;
		if (std::regex_match(name, m, withPid))
		{
			if (!alive(std::stol(m[2].str()))) out.push_back(it->path().string());
		}
		else if (std::regex_match(name, legacy))
			out.push_back(it->path().string());
	}
	std::sort(out.begin(), out.end());
	return out;
}

// ---------------------------------------------------------------- transaction
OutputTransaction::OutputTransaction() : mrpt::system::COutputLogger("shadyloc.outputs") {}

OutputTransaction::~OutputTransaction()
{
	if (!m_committed) rollback();
}

void OutputTransaction::rollback()
{
	std::lock_guard<std::recursive_mutex> lock(registryMutex());
	for (const auto& o : m_outputs)
	{
		std::error_code ec;
		fs::remove_all(o.tmp, ec);
		unregisterTemporary(o.tmp);
	}
}

void OutputTransaction::checkAgainst(const TEntry& out, const TEntry& other, bool otherIsInput) const
{
	const std::string a = out.what + " '" + out.path + "'";
	const std::string b = other.what + " '" + other.path + "'";
	if (out.canonical == other.canonical)
		throw std::invalid_argument(
			otherIsInput ? a + " is the " + b + ": an output may not replace an input"
						 : a + " and " + b + " are the same path: each output needs its own");
	if (other.ino != 0 && out.ino != 0 && other.dev == out.dev && other.ino == out.ino)
		throw std::invalid_argument(
			a + " is the same file as the " + b + " (a hard link)" +
			(otherIsInput ? ": an output may not replace an input" : ""));
	if (out.isDir && isInside(other.canonical, out.canonical))
		throw std::invalid_argument(a + " would replace the folder that holds the " + b);
	if (other.listed && isInside(out.canonical, other.canonical))
		throw std::invalid_argument(
			a + " lies inside the " + b + ", whose files are read as inputs: a later run would read it as one; "
			"write it outside that folder");
	if (!otherIsInput && other.isDir && isInside(out.canonical, other.canonical))
		throw std::invalid_argument(a + " lies inside the " + b + ", which is replaced as a whole");
}

void OutputTransaction::addListedFolder(const std::string& path, const std::string& what)
{
	addInput(path, what);
	m_inputs.back().listed = true;
	for (const auto& o : m_outputs) checkAgainst(o, m_inputs.back(), true);
}

void OutputTransaction::addInput(const std::string& path, const std::string& what)
{
	TEntry in;
	in.path = path;
	in.what = what;
	in.canonical = canonicalOf(path);
	struct stat st
	{
	};
	if (!path.empty() && ::stat(path.c_str(), &st) == 0)
	{
		in.dev = st.st_dev;
		in.ino = st.st_ino;
		in.isDir = S_ISDIR(st.st_mode);
	}
	for (const auto& o : m_outputs) checkAgainst(o, in, true);
	m_inputs.push_back(in);
}

bool OutputTransaction::hasOutput(const std::string& path) const
{
	const std::string c = canonicalOf(path);
	for (const auto& o : m_outputs)
		if (o.canonical == c) return true;
	return false;
}

std::string OutputTransaction::addFile(const std::string& path, const std::string& what)
{
	return reserve(path, what, false);
}

std::string OutputTransaction::addDirectory(const std::string& path, const std::string& what, const std::string& kind)
{
	if (kind.empty()) throw std::logic_error("OutputTransaction::addDirectory: no kind for '" + path + "'");
	// "out/" names the folder "out" (a file name could not end so).
	std::string p = path;
	while (p.size() > 1 && p.back() == '/') p.pop_back();
	return reserve(p, what, true, kind);
}

void OutputTransaction::reportStale(const std::string& dir)
{
	for (const auto& d : m_checkedDirs)
		if (d == dir) return;
	m_checkedDirs.push_back(dir);
	for (const auto& s : staleTemporaries(dir))
		MRPT_LOG_WARN_STREAM(
			"'" << s << "': temporary output left by an interrupted run; delete it with: rm -rf -- '" << s << "'");
}

std::string OutputTransaction::reserve(const std::string& path, const std::string& what, bool dir, const std::string& kind)
{
	if (m_committed) throw std::logic_error("OutputTransaction: outputs added after commit()");
	if (path.empty()) throw std::invalid_argument(what + ": the output path is empty");
	const fs::path p(path);
	const std::string name = p.filename().string();
	if (name.empty() || name == "." || name == "..")
		throw std::invalid_argument(
			what + " '" + path + "': names a directory, not an output " + (dir ? "folder" : "file"));
	const fs::path parent = p.parent_path().empty() ? fs::path(".") : p.parent_path();
	std::error_code ec;
	if (!fs::is_directory(parent, ec))
		throw std::invalid_argument(what + " '" + path + "': directory '" + parent.string() + "' does not exist");
	if (!dir && fs::is_directory(p, ec))
		throw std::invalid_argument(what + " '" + path + "': is a directory (a file name is expected)");
	if (dir && fs::exists(p, ec) && !fs::is_directory(p, ec))
		throw std::invalid_argument(what + " '" + path + "': exists and is not a directory");

	TEntry o;
	o.path = path;
	o.what = what;
	o.isDir = dir;
	o.canonical = canonicalOf(path);
	struct stat st
	{
	};
	if (::stat(path.c_str(), &st) == 0)
	{
		o.dev = st.st_dev;
		o.ino = st.st_ino;
	}
	for (const auto& in : m_inputs) checkAgainst(o, in, true);
	for (const auto& other : m_outputs) checkAgainst(o, other, false), checkAgainst(other, o, false);
	if (dir) checkReplaceableFolder(path, what, kind);

	reportStale(parent.string());
	o.tmp = siblingFor(path, "tmp", dir);
	registerTemporary(o.tmp);
	fs::remove_all(o.tmp, ec);
	if (dir && !fs::create_directory(o.tmp, ec))
		throw std::invalid_argument(
			what + " '" + path + "': cannot create the temporary folder '" + o.tmp + "': " + ec.message());
	m_outputs.push_back(o);	// from here on, rollback() removes the temporary
	if (dir) markOutputFolder(o.tmp, kind);
	return o.tmp;
}

void OutputTransaction::commit()
{
	if (m_committed) return;
	// Held throughout: a signal arriving now waits until every output is in
	// place (or every change is undone) before temporaries are removed.
	std::lock_guard<std::recursive_mutex> lock(registryMutex());
	for (const auto& o : m_outputs)
	{
		std::error_code ec;
		if (!fs::exists(o.tmp, ec))
			throw std::runtime_error(o.what + " '" + o.path + "': nothing was written to '" + o.tmp + "'");
	}
	struct TStep
	{
		const TEntry* o;
		std::string backup;	 //!< where the old output went ("" if none)
		bool renamed = false;
	};
	std::vector<TStep> steps;
	try
	{
		for (const auto& o : m_outputs)
		{
			TStep s{&o, "", false};
			std::error_code ec;
			if (fs::exists(fs::symlink_status(o.path, ec)))
			{
				s.backup = siblingFor(o.path, "old", o.isDir);
				registerTemporary(s.backup);
				fs::remove_all(s.backup, ec);
				fs::rename(o.path, s.backup);
			}
			steps.push_back(s);
			fs::rename(o.tmp, o.path);
			steps.back().renamed = true;
		}
	}
	catch (const std::exception& e)
	{
		// Undo in reverse: new outputs back to their temporaries, old ones back.
		for (auto it = steps.rbegin(); it != steps.rend(); ++it)
		{
			std::error_code ec;
			if (it->renamed) fs::rename(it->o->path, it->o->tmp, ec);
			if (!it->backup.empty())
			{
				fs::rename(it->backup, it->o->path, ec);
				unregisterTemporary(it->backup);
			}
		}
		rollback();
		throw std::runtime_error(std::string("cannot put the outputs in place (nothing changed): ") + e.what());
	}
	for (const auto& s : steps)
	{
		std::error_code ec;
		unregisterTemporary(s.o->tmp);
		if (!s.backup.empty())
		{
			fs::remove_all(s.backup, ec);
			unregisterTemporary(s.backup);
		}
	}
	m_committed = true;
}

}  // namespace shadyloc::io
