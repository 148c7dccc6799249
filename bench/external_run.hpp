// An external program timed side by side with floesim: the benches run
// another code (FloeDyn's FLOE, issue 23) on the same case between their own
// runs, so that the ratio they quote was measured on the same machine at the
// same load, not taken from another day.
//
// The program runs in its own process (fork, chdir, exec), with one OpenMP
// thread (OMP_NUM_THREADS=1, as the benches time floesim on one core) and
// its standard output and error sent to a log file; the wall time is the
// time from fork to exit.
#pragma once

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

namespace floesim::bench {

struct ExternalRun {
  bool ok = false;     // exited with status 0
  double wall = 0.0;   // s, fork to exit
  std::string status;  // "ok", "exit N", "signal N", "cannot run: ..."
};

// Runs `argv` (argv[0] the program's path) in folder `dir` (empty: this
// process's), output appended to `log`. Blocks until it exits.
inline ExternalRun run_external(const std::vector<std::string>& argv, const std::string& dir,
                                const std::string& log) {
  ExternalRun r;
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::fflush(stdout);
  std::fflush(stderr);
  const auto t0 = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid < 0) {
    r.status = "cannot run: fork failed";
    return r;
  }
  if (pid == 0) {
    const int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    if (fd >= 0) {
      dup2(fd, STDOUT_FILENO);
      dup2(fd, STDERR_FILENO);
      close(fd);
    }
    if (!dir.empty() && chdir(dir.c_str()) != 0) _exit(126);
    setenv("OMP_NUM_THREADS", "1", 1);
    execv(args[0], args.data());
    _exit(127);
  }
  int status = 0;
  if (waitpid(pid, &status, 0) != pid) {
    r.status = "cannot run: waitpid failed";
    return r;
  }
  r.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (WIFEXITED(status)) {
    const int code = WEXITSTATUS(status);
    r.ok = code == 0;
    r.status = code == 0     ? "ok"
               : code == 126 ? "cannot run: no folder " + dir
               : code == 127 ? "cannot run: cannot execute " + argv[0]
                             : "exit " + std::to_string(code);
  } else if (WIFSIGNALED(status)) {
    r.status = "signal " + std::to_string(WTERMSIG(status));
  }
  return r;
}

}  // namespace floesim::bench
