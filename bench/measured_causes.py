"""Counters read while the benchmarks run, and the cause sentences made of them.

run_benchmarks.py reads, at the edges of each measured stretch, the kernel's
counters of the server under load and of the reference it is compared with
(modbus_load --sync holds its clients, connected and idle, before they begin
and after they are done, until these reads are over):

  /proc/PID/stat            CPU time of the whole process, user and system
                            (threads that ended inside the stretch included)
  /proc/PID/task/TID/stat   a thread's name (comm)
  .../schedstat             a thread's CPU time and run-queue wait (ns), and
                            how often it was put on a CPU (its wake-ups, and
                            its returns after a preemption)
  .../status                voluntary and involuntary context switches
  .../wchan                 where a sleeping thread waits (to recognise the
                            control loop: it sleeps in clock_nanosleep or ppoll)
  /proc/stat                the whole machine's busy time: how full the cores
                            were, and what other processes (this VM is shared)
                            took

The single-threaded references (loop_floor, sqlite_commit) and the load
generator count themselves (getrusage and /proc/thread-self/schedstat around
what they time) and print it on their RESULT line.

A missed target's cause is then a sentence generated here from those figures
by fixed rules (which figure differs most from the reference, whether the
cores were full); nothing in it is written by hand or carried over from an
earlier run. Hardware counters (cycles, instructions) would add the work per
request; `perf stat` reports them as <not supported> on this VM (the counter
tables say what perf said in the run), so the kernel's scheduler counters are
what is used, and a software-clock profile: after the first round of each
Modbus TCP comparison, one more stretch of the same load, untimed, runs under
`perf record -e cpu-clock -g` on the server (perf slows what it samples, the
busier process more), and its samples are counted by the system call they
were in.
"""
import functools
import os
import statistics
import time

CLK_TCK = os.sysconf("SC_CLK_TCK")
NCPU = os.cpu_count() or 1


# --- reading ---------------------------------------------------------------------

def _read(path):
    try:
        with open(path) as f:
            return f.read()
    except OSError:
        return None


def _task(pid, tid):
    base = f"/proc/{pid}/task/{tid}"
    stat, sched, status = _read(base + "/stat"), _read(base + "/schedstat"), _read(base + "/status")
    if stat is None or sched is None or status is None:
        return None  # ended between the listing and the read
    comm = stat[stat.index("(") + 1:stat.rindex(")")]
    run_ns, wait_ns, slices = (int(x) for x in sched.split()[:3])
    vcs = ivcs = 0
    for line in status.splitlines():
        if line.startswith("voluntary_ctxt_switches:"):
            vcs = int(line.split()[1])
        elif line.startswith("nonvoluntary_ctxt_switches:"):
            ivcs = int(line.split()[1])
    return {"comm": comm, "run_ns": run_ns, "wait_ns": wait_ns, "slices": slices, "vcs": vcs, "ivcs": ivcs,
            "wchan": (_read(base + "/wchan") or "").strip()}


def machine_jiffies():
    """(busy, total) jiffies of all CPUs from /proc/stat (idle and iowait are not busy)."""
    fields = [int(x) for x in open("/proc/stat").readline().split()[1:]]
    total = sum(fields[:8])  # guest time is already inside user and nice
    return total - fields[3] - fields[4], total


def snapshot(pid):
    """Every counter of one process at one moment (the middle of the reads,
    which take a while for many threads); None if it is gone."""
    t0 = time.monotonic()
    stat = _read(f"/proc/{pid}/stat")
    if stat is None:
        return None
    f = stat[stat.rindex(")") + 2:].split()
    tasks = {}
    try:
        tids = os.listdir(f"/proc/{pid}/task")
    except OSError:
        return None
    for tid in tids:
        t = _task(pid, tid)
        if t:
            tasks[int(tid)] = t
    return {"t": (t0 + time.monotonic()) / 2, "pid": pid, "utime": int(f[11]) / CLK_TCK, "stime": int(f[12]) / CLK_TCK,
            "tasks": tasks, "machine": machine_jiffies()}


def snapshots(pids):
    return {pid: snapshot(pid) for pid in pids}


# --- one stretch -----------------------------------------------------------------

SLEEPS_OF_A_PERIODIC_LOOP = ("nanosleep", "poll_schedule_timeout", "do_sys_poll")


def stretch(a, b):
    """The counters of one process between snapshots a and b."""
    secs = max(b["t"] - a["t"], 1e-9)
    busy = b["machine"][0] - a["machine"][0]
    total = max(b["machine"][1] - a["machine"][1], 1)
    threads = []
    order = sorted(set(a["tasks"]) | set(b["tasks"]))
    for tid in sorted(b["tasks"]):
        t1 = b["tasks"][tid]
        t0 = a["tasks"].get(tid, {"run_ns": 0, "wait_ns": 0, "slices": 0, "vcs": 0, "ivcs": 0})
        threads.append({"tid": tid, "comm": t1["comm"], "main": tid == b["pid"],
                        "start_rank": order.index(tid),
                        "cpu_s": (t1["run_ns"] - t0["run_ns"]) / 1e9, "wait_s": (t1["wait_ns"] - t0["wait_ns"]) / 1e9,
                        "slices": t1["slices"] - t0["slices"], "vcs": t1["vcs"] - t0["vcs"],
                        "ivcs": t1["ivcs"] - t0["ivcs"],
                        "wchans": {a["tasks"].get(tid, {}).get("wchan", ""), t1["wchan"]}})
    user, system = b["utime"] - a["utime"], b["stime"] - a["stime"]
    # CPU: the threads' schedstat (nanoseconds) is exact; the process's utime +
    # stime also counts threads that ended in the stretch but comes in clock
    # ticks (1/CLK_TCK: 10 ms here, what an idle daemon uses in a second), so it
    # only adds what ended threads used.
    seen_cpu = sum(t["cpu_s"] for t in threads)
    ended = set(a["tasks"]) - set(b["tasks"])
    cpu = seen_cpu + (max(user + system - seen_cpu, 0.0) if ended else 0.0)
    return {"seconds": secs, "user_s": user, "sys_s": system, "cpu_s": cpu,
            "threads": threads, "ended": len(ended),
            "busy_cores": busy / total * NCPU,
            "vcs": sum(t["vcs"] for t in threads), "ivcs": sum(t["ivcs"] for t in threads),
            "wait_s": sum(t["wait_s"] for t in threads), "slices": sum(t["slices"] for t in threads)}


CONTROL_THREAD_NAME = "control"  # homingd names its control loop's thread so (pthread_setname_np)


def control_thread(s):
    """homingd's control loop: the thread named CONTROL_THREAD_NAME; in a
    homingd that does not name its threads, the first thread it starts
    (ControlLoop::start is the first thing serve() in server/daemon.cpp does),
    confirmed when it was seen asleep where a periodic loop sleeps
    (clock_nanosleep, or ppoll when idle). Returns (thread, confirmed) or
    (None, False)."""
    others = [t for t in s["threads"] if not t["main"]]
    if not others:
        return None, False
    named = [t for t in others if t["comm"] == CONTROL_THREAD_NAME]
    if named:
        return named[0], True
    first = min(others, key=lambda t: t["start_rank"])
    confirmed = any(w.startswith(SLEEPS_OF_A_PERIODIC_LOOP) or "nanosleep" in w for w in first["wchans"])
    return first, confirmed


@functools.lru_cache(maxsize=None)
def hardware_counters():
    """Whether perf can count cycles and instructions here, as perf itself says
    (a sentence for BENCHMARKS.md); read once per run."""
    import shutil
    import subprocess
    if not shutil.which("perf"):
        return "not read: perf is not installed"
    try:
        p = subprocess.run(["perf", "stat", "-x,", "-e", "instructions,cycles", "true"], capture_output=True,
                           text=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired) as e:
        return f"not read: perf stat failed ({e})"
    lines = [x for x in p.stderr.splitlines() if ",instructions," in x or ",cycles," in x]
    if not lines or any(x.startswith("<not") for x in lines):
        return "not available on this machine (`perf stat -e instructions,cycles true` reports them <not supported>)"
    return "available on this machine, but not read by this benchmark yet"


# --- a profile: where the CPU goes, by system call ----------------------------------

class Profile:
    """perf record of one process over a measured stretch (software cpu-clock
    samples: this VM has no hardware counters), started disabled and enabled
    through perf's control FIFO, so it covers the stretch and not perf's own
    start. None of it when perf is missing or refuses."""

    def __init__(self, pid, path):
        self.path, self.proc = path, None
        import shutil
        import subprocess
        if not shutil.which("perf"):
            return
        self.ctl, self.ack = path + ".ctl", path + ".ack"
        for f in (self.ctl, self.ack):
            os.mkfifo(f)
        self.proc = subprocess.Popen(self.argv(pid, path, f"fifo:{self.ctl},{self.ack}"),
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        # perf opens the FIFOs once attached; until then opening the control
        # FIFO for writing fails (ENXIO). Never block on a perf that failed.
        import errno
        import fcntl
        end = time.monotonic() + 10
        self.ctl_fd = None
        while self.ctl_fd is None and self.proc.poll() is None and time.monotonic() < end:
            try:
                self.ctl_fd = os.open(self.ctl, os.O_WRONLY | os.O_NONBLOCK)
            except OSError as e:
                if e.errno != errno.ENXIO:
                    raise
                time.sleep(0.01)
        if self.ctl_fd is None:
            self._give_up()
            return
        self.ack_fd = os.open(self.ack, os.O_RDONLY | os.O_NONBLOCK)
        fcntl.fcntl(self.ack_fd, fcntl.F_SETFL, 0)  # blocking from here: perf holds the writing end

    @staticmethod
    def argv(pid, path, control="fifo:CTL,ACK"):
        return ["perf", "record", "-q", "-e", "cpu-clock", "-F", "499", "-g", "-D", "-1", "--control", control,
                "-p", str(pid), "-o", path]

    def _give_up(self):
        if self.proc.poll() is None:
            self.proc.kill()
        self.proc.wait()
        self.proc = None

    def _command(self, what):
        import select
        os.write(self.ctl_fd, (what + "\n").encode())
        # "ack\n" once perf has done it (EOF if perf is gone); never wait long for a stuck perf.
        if select.select([self.ack_fd], [], [], 10)[0]:
            os.read(self.ack_fd, 16)

    def enable(self):
        if self.proc:
            self._command("enable")

    def disable(self):
        if self.proc:
            self._command("disable")

    def finish(self):
        """Stops perf; returns {"samples": n, "by_call": {name: share}} or None."""
        if not self.proc:
            return None
        import signal
        import subprocess
        os.close(self.ctl_fd)
        os.close(self.ack_fd)
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(timeout=30)
        except subprocess.TimeoutExpired:
            self._give_up()
            return None
        out = subprocess.run(["perf", "script", "-i", self.path, "-F", "tid,ip,sym"], capture_output=True,
                             text=True, timeout=120).stdout
        return by_system_call(out)


def by_system_call(script):
    """perf script's samples (a header line, then the call chain leaf first)
    bucketed by the system call they were in (the __x64_sys_* frame), or
    "user space", or "kernel outside a system call" (interrupts, softirqs)."""
    counts, n = {}, 0
    for block in script.split("\n\n"):
        lines = [x.split() for x in block.strip().splitlines()[1:]]
        if not lines:
            continue
        n += 1
        syms = [x[1] if len(x) > 1 else "?" for x in lines]
        kernel = [x for x in lines if len(x) > 1 and x[0].startswith("ffff")]
        call = next((sym for sym in syms if sym.startswith(("__x64_sys_", "__ia32_sys_", "__arm64_sys_",
                                                            "__do_sys_"))), None)
        if call:
            name = call.split("sys_", 1)[1]
        elif kernel and lines[0][0].startswith("ffff"):
            name = "kernel outside a system call"
        else:
            name = "user space"
        counts[name] = counts.get(name, 0) + 1
    return {"samples": n, "by_call": {k: v / n for k, v in counts.items()}} if n else None


# What a system call's time means for a server here (for the sentence only).
CALL_MEANING = {"futex": "threads waiting for and waking each other", "poll": "waiting on sockets",
                "ppoll": "waiting on sockets", "select": "waiting on sockets", "pselect6": "waiting on sockets",
                "epoll_wait": "waiting on sockets", "recvfrom": "receiving", "read": "reading",
                "sendto": "sending", "write": "writing", "clock_nanosleep": "a loop's sleep",
                "user space": "its own code and libraries", "fsync": "the disk's flush",
                "fdatasync": "the disk's flush"}


def profile_sentence(hp, rp, h_cpu_us, r_cpu_us, who="bare libmodbus"):
    """The largest extra CPU per request by system call, homingd against the reference."""
    if not hp or not rp:
        return ""
    def top(p, k=4):
        return ", ".join(f"{name} {share * 100:.0f} %" for name, share in
                         sorted(p["by_call"].items(), key=lambda x: -x[1])[:k])
    diffs = {name: hp["by_call"].get(name, 0) * h_cpu_us - rp["by_call"].get(name, 0) * r_cpu_us
             for name in set(hp["by_call"]) | set(rp["by_call"])}
    name, extra = max(diffs.items(), key=lambda x: x[1])
    s = (f"Profile of one more stretch of round 1's load, untimed (perf record, cpu-clock, {hp['samples']} and {rp['samples']} samples), CPU by system "
         f"call: homingd {top(hp)}; {who} {top(rp)}.")
    if extra > 0:
        meaning = CALL_MEANING.get(name)
        s += (f" The largest extra is {name}{f' ({meaning})' if meaning else ''}: {_n(extra)} µs per request more "
              f"than {who}.")
    return s


def children_rusage():
    import resource
    return resource.getrusage(resource.RUSAGE_CHILDREN)


def children_stretch(ru0, m0):
    """Counters of the child processes waited for since (ru0, m0) (run_benchmarks
    runs one program at a time there), and how busy the machine was."""
    ru1, m1 = children_rusage(), machine_jiffies()
    return {"user_s": ru1.ru_utime - ru0.ru_utime, "sys_s": ru1.ru_stime - ru0.ru_stime,
            "vcs": ru1.ru_nvcsw - ru0.ru_nvcsw, "ivcs": ru1.ru_nivcsw - ru0.ru_nivcsw,
            "busy": (m1[0] - m0[0]) / max(m1[1] - m0[1], 1) * NCPU}


def thread_groups(s):
    """CPU seconds of a stretch by thread, threads grouped by name (a number at
    the end of a name is one of several alike: "tcp-loop-0", "tcp-loop-1" make
    "tcp-loop-N"); threads the program does not name go by role."""
    import re
    ctl, _ = control_thread(s)
    comm = next((t["comm"] for t in s["threads"] if t["main"]), None)
    out = {}
    for t in s["threads"]:
        if t["main"]:
            g = "main thread"
        elif ctl is not None and t["tid"] == ctl["tid"]:
            g = "control loop"
        elif t["comm"] != comm:
            g = re.sub(r"\d+$", "N", t["comm"])
        else:
            g = "unnamed threads"
        out[g] = out.get(g, 0.0) + t["cpu_s"]
    return out


def self_counters(result):
    """The counters a reference or the load generator printed on its RESULT line."""
    if "cpu_user_us" not in result:
        return None
    return {"user_s": result["cpu_user_us"] / 1e6, "sys_s": result["cpu_sys_us"] / 1e6,
            "cpu_s": (result["cpu_user_us"] + result["cpu_sys_us"]) / 1e6, "vcs": result["vcs"],
            "ivcs": result["ivcs"], "wait_s": result.get("rq_wait_us", 0) / 1e6, "slices": result.get("slices", 0)}


# The kernel splits CPU time into user and system in proportion to the clock
# ticks that found the thread in each (utime and stime are tick samples scaled
# to the exact total), so a split of fewer ticks than this is left out.
MIN_TICKS_FOR_SPLIT = 20


def kernel_share(user_s, sys_s):
    if (user_s + sys_s) * CLK_TCK < MIN_TICKS_FOR_SPLIT:
        return None
    return sys_s / (user_s + sys_s)


def serving_threads(s):
    """The threads that can serve requests, whatever the server's design (a
    thread per connection, event loops, a writer): all but homingd's control
    loop (reported on its own, it only runs periods) and the main thread of a
    multi-threaded process (it waits for signals); a single-threaded server's
    one thread."""
    if len(s["threads"]) <= 1:
        return list(s["threads"])
    ctl, _ = control_thread(s)
    return [t for t in s["threads"] if not t["main"] and (ctl is None or t["tid"] != ctl["tid"])]


def per_request(server, requests, client=None, seconds=None):
    """Figures per request of a server stretch (and of its load generator);
    seconds: the load's own length, over which the cores are counted (the
    counters' stretch also holds the short idle moments of their reading)."""
    n = max(requests, 1)
    secs = seconds or server.get("seconds")
    cpu = server["cpu_s"]
    serving = serving_threads(server) if "threads" in server else []
    out = {"cpu_us": cpu / n * 1e6, "kernel": kernel_share(server["user_s"], server["sys_s"]),
           "serving": len(serving), "serving_wait_us": sum(t["wait_s"] for t in serving) / n * 1e6
           if "threads" in server else server["wait_s"] / n * 1e6,
           "cs": (server["vcs"] + server["ivcs"]) / n, "ivcs": server["ivcs"] / n,
           "wait_us": server["wait_s"] / n * 1e6, "threads": len(server.get("threads", [])) or 1,
           "user_us": server["user_s"] / n * 1e6, "sys_us": server["sys_s"] / n * 1e6,
           "cores": cpu / secs if secs else None, "busy": server.get("busy_cores")}
    if client:
        out["client_cpu_us"] = client["cpu_s"] / n * 1e6
        out["client_cores"] = client["cpu_s"] / secs if secs else None
    if out["busy"] is not None and out["cores"] is not None:
        out["others"] = max(out["busy"] - out["cores"] - (out.get("client_cores") or 0), 0.0)
    return out


def loop_figures(t, seconds):
    """A periodic loop thread's figures: wake-ups/s, CPU and run-queue wait per wake-up."""
    slices = max(t["slices"], 1)
    return {"wakes": t["slices"] / seconds, "cpu_us": t["cpu_s"] / slices * 1e6, "wait_us": t["wait_s"] / slices * 1e6,
            "ivcs": t["ivcs"] / seconds, "cores": t["cpu_s"] / seconds}


def medians(dicts):
    """Median of each key over the rounds (keys with a value in every round)."""
    dicts = [d for d in dicts if d]
    if not dicts:
        return None
    out = {}
    for k in dicts[0]:
        vals = [d.get(k) for d in dicts]
        if all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in vals):
            out[k] = statistics.median(vals)
        elif all(v is None or isinstance(v, (int, float)) for v in vals):
            known = [v for v in vals if v is not None]
            out[k] = statistics.median(known) if known else None
    return out


# --- wording ---------------------------------------------------------------------

def _n(v, digits=1):
    if v is None:
        return "–"
    if abs(v) >= 100:
        return f"{v:,.0f}"
    return f"{v:.{digits}f}"


def _kern(v):
    """' (N % kernel)', or nothing when too few clock ticks were counted to split."""
    return "" if v is None else f" ({v * 100:.0f} % kernel)"


def _groups(groups, k=5):
    return ", ".join(f"{name} {cores:.2f}" for name, cores in sorted(groups.items(), key=lambda x: -x[1])[:k])


def _threads(n):
    return f"{n:.0f} thread{'' if round(n) == 1 else 's'}"


def _pct(v):
    return "–" if v is None else f"{v * 100:.0f} %"


def _times(a, b):
    """a / b as 'N×' (b the reference)."""
    return f"{a / b:.1f}×" if b else "–"


def _largest(pairs):
    """pairs: (label, homingd, reference); the one whose ratio homingd/reference is largest."""
    best = None
    for label, h, r in pairs:
        if r and r > 0 and h is not None:
            q = h / r
            if best is None or q > best[1]:
                best = (label, q)
    return best


def _requests(x):
    return x.get("requests") or 0


# --- throughput and p99, per client count ------------------------------------------

def throughput_figures(rows):
    """Per-round figures of homingd and of the bare server (medians over the rounds)."""
    out = {}
    groups = []
    for who in ("bare", "homingd"):
        per = []
        for res, cnt in zip(rows[who], rows.get("cnt_" + who, [])):
            if cnt is None:
                continue
            f = per_request(cnt, _requests(res), self_counters(res), res.get("seconds"))
            if who == "homingd":
                secs = res.get("seconds") or cnt["seconds"]
                groups.append({g: c / secs for g, c in thread_groups(cnt).items()})
                ctl, ok = control_thread(cnt)
                if ctl:
                    f["control_cores"] = ctl["cpu_s"] / cnt["seconds"]
                    f["control_cpu_us"] = ctl["cpu_s"] / max(_requests(res), 1) * 1e6
                    f["control_confirmed"] = 1.0 if ok else 0.0
            per.append(f)
        out[who] = medians(per)
        if out[who] is not None:
            out[who]["profile"] = next((c["profile"] for c in rows.get("cnt_" + who, []) if c and c.get("profile")),
                                       None)
    if out.get("homingd") is not None:
        keys = {k for g in groups for k in g}
        out["homingd"]["groups"] = {k: statistics.median(g.get(k, 0.0) for g in groups) for k in keys}
    return out if out.get("bare") and out.get("homingd") else None


def throughput_cause(clients, rows, ratio):
    """Requests per second = cores the server and load generator got / their CPU
    per request, so the ratio splits into two measured factors; the smaller
    one names the cause."""
    f = throughput_figures(rows)
    if not f:
        return None
    h, r = f["homingd"], f["bare"]
    hc = h["cpu_us"] + h.get("client_cpu_us", 0)
    rc = r["cpu_us"] + r.get("client_cpu_us", 0)
    got_h = (h["cores"] or 0) + (h.get("client_cores") or 0)
    got_r = (r["cores"] or 0) + (r.get("client_cores") or 0)
    cpu_factor, core_factor = rc / hc, got_h / max(got_r, 1e-9)
    s = [_evidence(h, r),
         f"The ratio is two measured factors: the CPU per request of server and load generator together, "
         f"{_n(hc)} µs against {_n(rc)} ({cpu_factor:.2f}×), times the cores they got, {got_h:.2f} against "
         f"{got_r:.2f} ({core_factor:.2f}×): {cpu_factor * core_factor:.2f}× (measured {ratio:.2f}×)."]
    if cpu_factor <= core_factor:
        part = [f"The larger loss is homingd's CPU per request, {_n(h['cpu_us'] - r['cpu_us'])} µs more than the "
                "bare server's"]
        if h["kernel"] is not None and r["kernel"] is not None:
            part[0] += (f" (user time {_n(h['user_us'])} µs against {_n(r['user_us'])}, kernel {_n(h['sys_us'])} "
                        f"against {_n(r['sys_us'])})")
        if "control_cpu_us" in h:
            part.append(f"{_n(h['control_cpu_us'])} µs per request is its control loop's ({h['control_cores']:.2f} "
                        "of a core)")
        if len(h.get("groups", {})) > 2:
            part.append("its threads' cores: " + _groups(h["groups"]))
        s.append("; ".join(part) + ".")
        s.append(profile_sentence(h["profile"], r["profile"], h["cpu_us"], r["cpu_us"]))
    else:
        idle_h, idle_r = max(NCPU - h["busy"], 0), max(NCPU - r["busy"], 0)
        more_others, more_idle = h.get("others", 0) - r.get("others", 0), idle_h - idle_r
        if max(more_others, more_idle) < 0.05:
            s.append(f"The larger loss is the cores, {got_r - got_h:.2f} fewer, yet neither other processes nor "
                     "idle time took more of them during homingd's rounds; the counters' stretch and the load's "
                     "differ by the moments the counters take to read.")
        elif more_others >= more_idle:
            s.append(f"The larger loss is the cores: other processes on this shared VM took {h.get('others', 0):.2f} "
                     f"cores during homingd's rounds against {r.get('others', 0):.2f} during the bare server's, "
                     "a condition of this machine in these rounds, not homingd's cost (compare the rounds).")
        else:
            s.append(f"The larger loss is the cores: {idle_h:.2f} of {NCPU} stood idle during homingd's rounds "
                     f"({idle_r:.2f} during the bare server's), so the requests waited rather than computed: "
                     + _waiting(h, r))
    return " ".join(x for x in s if x)


def p99_cause(clients, rows):
    f = throughput_figures(rows)
    if not f:
        return None
    h, r = f["homingd"], f["bare"]
    s = [_evidence(h, r)]
    big = _largest([("run-queue wait per request", h["serving_wait_us"], r["serving_wait_us"]),
                    ("involuntary context switches per request", h["ivcs"], r["ivcs"]),
                    ("context switches per request", h["cs"], r["cs"]),
                    ("CPU per request", h["cpu_us"], r["cpu_us"])])
    if big:
        s.append(f"The largest difference is the {big[0]} ({big[1]:.1f}× the bare server's): " +
                 {"run-queue wait per request": "a request's answer waits for its thread to get a core, and that "
                  "wait, not the work, makes the tail.",
                  "involuntary context switches per request": "threads are preempted in the middle of a request, "
                  "and a preempted answer waits a time slice, which makes the tail.",
                  "context switches per request": "each request costs more sleeps and wake-ups, each a chance to "
                  "wait behind another runnable thread.",
                  "CPU per request": "the work per request itself is larger, and the tail scales with it."}[big[0]])
    if h["threads"] > r["threads"]:
        s.append(f"homingd ran {h['threads']:.0f} threads during the load, the bare server {r['threads']:.0f}.")
    spread = {who: _median_of(rows.get(who, []), "client_spread") for who in ("homingd", "bare")}
    if clients > 1 and spread["homingd"] is not None and spread["bare"] is not None:
        s.append(f"How evenly the clients were served (requests per client, 10th percentile over 90th, 1 = alike): "
                 f"homingd {spread['homingd']:.2f}, bare libmodbus {spread['bare']:.2f}" +
                 (": some clients waited while others went round again." if spread["homingd"] < spread["bare"] - 0.05
                  else "."))
    if big and big[0] == "CPU per request":
        s.append(profile_sentence(h["profile"], r["profile"], h["cpu_us"], r["cpu_us"]))
    return " ".join(x for x in s if x)


def _median_of(results, key):
    values = [res[key] for res in results if isinstance(res, dict) and isinstance(res.get(key), float)]
    return statistics.median(values) if values else None


def _evidence(h, r):
    return (f"Measured in these rounds (medians): homingd {_n(h['cpu_us'])} µs CPU per request"
            f"{_kern(h['kernel'])}, {_n(h['cs'], 2)} context switches per request ({_n(h['ivcs'], 2)} "
            f"involuntary), {_n(h['serving_wait_us'])} µs per request waiting for a core in its "
            f"{_threads(h['serving'])} other than the control loop; bare libmodbus {_n(r['cpu_us'])} µs"
            f"{_kern(r['kernel'])}, {_n(r['cs'], 2)} ({_n(r['ivcs'], 2)}), {_n(r['serving_wait_us'])} µs in its "
            f"{_threads(r['serving'])}. The load "
            f"generator: {_n(h.get('client_cpu_us'))} µs CPU per request against homingd, "
            f"{_n(r.get('client_cpu_us'))} µs against the bare server.")


def _waiting(h, r):
    return (f"{_n(h['serving_wait_us'])} µs per request waiting for a core against {_n(r['serving_wait_us'])} µs "
            f"({_times(h['serving_wait_us'], r['serving_wait_us'])}), {_n(h['cs'], 2)} context switches per request "
            f"against "
            f"{_n(r['cs'], 2)} ({_times(h['cs'], r['cs'])}).")


def throughput_table(tp):
    """The counters beside the throughput figures (BENCHMARKS.md lines)."""
    L = ["Counters of the same rounds (medians; `/proc/PID/stat`, `/proc/PID/task/*/{schedstat,status}` read when "
         "the clients begin and when they are done; the load generator counts itself): CPU per request with its "
         "kernel share (– when too few clock ticks were counted to split), context switches per request "
         "(involuntary in brackets), time per request the server's threads other than homingd's control loop and "
         "main thread (those that serve requests, whatever the design) waited on a run queue for a core, the "
         "server's threads (of them serving), the load generator's CPU per request, and how many of the "
         f"{NCPU} cores the whole machine kept busy (by other processes, this script included). Hardware counters "
         f"(cycles, instructions per request): {hardware_counters()}.",
         "",
         "| clients | server | CPU µs/req | kernel | ctx switches/req | run-queue wait µs/req | threads (serving) | "
         "load generator CPU µs/req | cores busy (others) |",
         "|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    any_row = False
    for clients in sorted(tp):
        f = throughput_figures(tp[clients])
        if not f:
            continue
        any_row = True
        for who, label in (("bare", "bare libmodbus"), ("homingd", "**homingd**")):
            x = f[who]
            L.append(f"| {clients} | {label} | {_n(x['cpu_us'])} | {_pct(x['kernel'])} | {_n(x['cs'], 2)} "
                     f"({_n(x['ivcs'], 2)}) | {_n(x['serving_wait_us'])} | {x['threads']:.0f} ({x['serving']:.0f}) "
                     f"| {_n(x.get('client_cpu_us'))} "
                     f"| {x['busy']:.2f} ({x.get('others', 0):.2f}) |")
    L.append("")
    by = [(c, throughput_figures(tp[c])) for c in sorted(tp)]
    by = [(c, f["homingd"]["groups"]) for c, f in by if f and f["homingd"].get("groups")]
    if by and any(len(g) > 3 for _, g in by):  # worth a line only when homingd names its threads
        L += ["homingd's CPU by thread in the same rounds (cores, medians; threads grouped by the name homingd gives "
              "them, a final number as N):", ""]
        L += [f"- {c} client{'s' if c > 1 else ''}: {_groups(g, 8)}" for c, g in by]
        L.append("")
    prof = [(c, throughput_figures(tp[c])) for c in sorted(tp)]
    prof = [(c, f) for c, f in prof if f and f["homingd"]["profile"] and f["bare"]["profile"]]
    if prof:
        L += ["Where the servers' CPU went (`perf record -e cpu-clock -g` over one more stretch of round 1's load, "
              "untimed: perf slows what it samples; each "
              "sample counted under the system call it was in, else user space or the kernel outside a system call; "
              "the four largest shares):", "",
              "| clients | server | samples | CPU by system call |", "|---:|---|---:|---|"]
        for c, f in prof:
            for who, label in (("bare", "bare libmodbus"), ("homingd", "**homingd**")):
                pr = f[who]["profile"]
                top = ", ".join(f"{name} {share * 100:.0f} %" for name, share in
                                sorted(pr["by_call"].items(), key=lambda x: -x[1])[:4])
                L.append(f"| {c} | {label} | {pr['samples']} | {top} |")
        L.append("")
    return L if any_row else []


# --- the control loop under load -------------------------------------------------

def loop_figures_of(rows, period_us=1000):
    """homingd's control thread and the bare loop (period_us: loop_floor's
    --period-us, to turn its periods into seconds), medians over the rounds."""
    hs, rs = [], []
    for cnt, lf in zip(rows.get("cnt_homingd", []), rows.get("loop_floor", [])):
        if cnt is None:
            continue
        ctl, ok = control_thread(cnt)
        if ctl:
            f = loop_figures(ctl, cnt["seconds"])
            f["others_cores"] = (cnt["cpu_s"] - ctl["cpu_s"]) / cnt["seconds"]
            f["busy"] = cnt["busy_cores"]
            f["confirmed"] = 1.0 if ok else 0.0
            hs.append(f)
        sc = self_counters(lf)
        if sc:
            secs = lf["periods"] * period_us / 1e6 if lf.get("periods") else 1.0
            rs.append({"wakes": sc["slices"] / secs, "cpu_us": sc["cpu_s"] / max(sc["slices"], 1) * 1e6,
                       "wait_us": sc["wait_s"] / max(sc["slices"], 1) * 1e6, "ivcs": sc["ivcs"] / secs})
    rb = []
    for cnt in rows.get("cnt_bare", []):
        if cnt:
            rb.append({"busy": cnt["busy_cores"], "server_cores": cnt["cpu_s"] / cnt["seconds"]})
    h, r = medians(hs), medians(rs)
    if h is None or r is None:
        return None
    r.update(medians(rb) or {})
    return {"homingd": h, "bare": r}


def loop_cause(clients, rows, period_us=1000):
    f = loop_figures_of(rows, period_us)
    if not f:
        return None
    h, r = f["homingd"], f["bare"]
    who = "homingd's control thread" if h.get("confirmed", 0) >= 0.5 else \
        "homingd's first-started thread (taken for the control loop; not seen asleep in its sleep call)"
    s = [f"Measured in these rounds (medians): {who} woke {_n(h['wakes'], 0)} times a second, used "
         f"{_n(h['cpu_us'])} µs CPU per wake-up, waited {_n(h['wait_us'])} µs per wake-up on a run queue before it "
         f"ran and was preempted {_n(h['ivcs'])} times a second; the bare loop {_n(r['wakes'], 0)}/s, "
         f"{_n(r['cpu_us'])} µs, {_n(r['wait_us'])} µs, {_n(r['ivcs'])}/s."]
    competing = (f"Competing for the {NCPU} cores: homingd's other threads used {h['others_cores']:.2f} cores (the "
                 f"bare server {r.get('server_cores', float('nan')):.2f}), the machine was {h['busy']:.2f} busy "
                 f"({r.get('busy', float('nan')):.2f} in the bare round).")
    if h["cpu_us"] > 0.5 * period_us:
        s.append(f"The loop's own work ({_n(h['cpu_us'])} µs per period) fills more than half the period, so a "
                 "period that takes longer makes the next one late.")
    elif h["wait_us"] > 1.2 * r["wait_us"]:
        s.append(f"Its mean wait for a core is {h['wait_us'] / max(r['wait_us'], 1e-9):.1f}× the bare loop's: the "
                 "loop is late because it waits for a core, not because of its own work. " + competing)
    elif h["ivcs"] > 1.2 * r["ivcs"] and h["ivcs"] >= 1:
        s.append("It is preempted more often than the bare loop: a preempted period ends a time slice later. "
                 + competing)
    else:
        s.append(f"Neither its mean wait for a core nor its preemptions are worse than the bare loop's, and its work "
                 f"per period ({_n(h['cpu_us'])} µs) is far below the period: the p99 comes from rare long delays "
                 "that the means do not show (this VM's scheduler hiccups; compare the rounds). " + competing)
    return " ".join(s)


def loop_table(tp):
    L = ["Counters of the loops in the same rounds (medians): wake-ups per second, CPU and run-queue wait per "
         "wake-up (`schedstat`), preemptions (involuntary context switches) per second. homingd's control thread "
         "is the first thread it starts (server/daemon.cpp) and is recognised by where it sleeps "
         "(`/proc/PID/task/TID/wchan`).",
         "",
         "| clients | loop | wake-ups/s | CPU µs/wake-up | run-queue wait µs/wake-up | preemptions/s | cores busy |",
         "|---:|---|---:|---:|---:|---:|---:|"]
    any_row = False
    for clients in sorted(tp):
        f = loop_figures_of(tp[clients])
        if not f:
            continue
        any_row = True
        for who, label in (("bare", "bare loop"), ("homingd", "**homingd** control thread")):
            x = f[who]
            L.append(f"| {clients} | {label} | {_n(x['wakes'], 0)} | {_n(x['cpu_us'])} | {_n(x['wait_us'])} "
                     f"| {_n(x['ivcs'])} | {_n(x.get('busy'), 2)} |")
    L.append("")
    return L if any_row else []


# --- idle ------------------------------------------------------------------------

def idle_figures(idl):
    hs, rs, tops = [], [], []
    for cnt, fc in zip(idl.get("cnt_homingd", []), idl.get("cnt_floor", [])):
        if not cnt or not fc:
            continue
        secs = cnt["seconds"]
        wakes = cnt["slices"] / secs
        hs.append({"cpu_pct": cnt["cpu_s"] / secs * 100, "wakes": wakes,
                   "cpu_us": cnt["cpu_s"] / max(cnt["slices"], 1) * 1e6, "threads": len(cnt["threads"])})
        ctl, _ = control_thread(cnt)
        comm = next((t["comm"] for t in cnt["threads"] if t["main"]), None)
        tops.append([(_role(t, ctl, comm), t["slices"] / secs, t["cpu_s"] / secs * 100) for t in cnt["threads"]])
        fsecs = fc["seconds"]
        rs.append({"cpu_pct": fc["cpu_s"] / fsecs * 100, "wakes": fc["slices"] / fsecs,
                   "cpu_us": fc["cpu_s"] / max(fc["slices"], 1) * 1e6})
    h, r = medians(hs), medians(rs)
    if not h or not r:
        return None
    # Per thread: the median over the rounds of each role's wake-ups and CPU.
    roles = {}
    for rnd in tops:
        for role, w, c in rnd:
            roles.setdefault(role, []).append((w, c))
    threads = sorted(((role, statistics.median(x[0] for x in v), statistics.median(x[1] for x in v))
                      for role, v in roles.items()), key=lambda x: -x[2])
    return {"homingd": h, "bare": r, "threads": threads}


def _role(t, ctl, process_comm):
    """A thread's name in the tables: its own when the program names it (comm
    other than the process's), else its role or its place in start order."""
    if t["main"]:
        return "main thread"
    if ctl is not None and t["tid"] == ctl["tid"]:
        return "control loop" + (f" (\"{t['comm']}\")" if t["comm"] != process_comm else "")
    if t["comm"] != process_comm:
        return f"\"{t['comm']}\" (started {_ordinal(t['start_rank'])})"
    return f"thread started {_ordinal(t['start_rank'])}"


def _ordinal(n):
    return f"{n}{'th' if 10 <= n % 100 <= 20 else {1: 'st', 2: 'nd', 3: 'rd'}.get(n % 10, 'th')}"


def idle_cause(idl):
    f = idle_figures(idl)
    if not f:
        return None
    h, r = f["homingd"], f["bare"]
    per = ", ".join(f"{role} {_n(w, 0)}/s ({c:.2f} %)" for role, w, c in f["threads"] if w >= 0.5 or c >= 0.01)
    s = [f"Measured in these rounds (medians, `schedstat`): homingd woke {_n(h['wakes'], 0)} times a second in "
         f"{h['threads']:.0f} threads ({per}), {_n(h['cpu_us'])} µs CPU per wake-up; the bare loop "
         f"{_n(r['wakes'], 0)} times a second, {_n(r['cpu_us'])} µs per wake-up."]
    # Split the ratio into the wake-up rate and the cost of one wake-up.
    rate, cost = h["wakes"] / max(r["wakes"], 1e-9), h["cpu_us"] / max(r["cpu_us"], 1e-9)
    s.append(f"homingd's CPU is {rate:.2f}× the bare loop's wake-ups times {cost:.1f}× its CPU per wake-up.")
    if f["threads"]:
        top = f["threads"][0]
        s.append(f"The most CPU: the {top[0]}, {top[2]:.2f} % of a core at {_n(top[1], 0)} wake-ups a second.")
    if cost > 1.5:
        s.append(f"To meet 0.30× at this CPU per wake-up homingd may wake at most "
                 f"{_n(0.3 * r['wakes'] / cost, 0)} times a second; at this wake-up rate one wake-up may cost at "
                 f"most {_n(0.5e4 / max(h['wakes'], 1e-9))} µs for < 0.5 %.")
    return " ".join(s)


def idle_table(idl):
    f = idle_figures(idl)
    if not f:
        return []
    L = ["Counters of the same stretches (medians over the rounds; `/proc/PID/task/*/schedstat`: a time slice is "
         "one wake-up; threads by role, the control loop recognised as under load):",
         "",
         "| process / thread | wake-ups/s | CPU, % of one core | CPU µs per wake-up |",
         "|---|---:|---:|---:|",
         f"| bare 1 ms loop | {_n(f['bare']['wakes'], 0)} | {f['bare']['cpu_pct']:.2f} % | {_n(f['bare']['cpu_us'])} |",
         f"| **homingd**, all threads | {_n(f['homingd']['wakes'], 0)} | {f['homingd']['cpu_pct']:.2f} % "
         f"| {_n(f['homingd']['cpu_us'])} |"]
    for role, w, c in f["threads"]:
        L.append(f"| homingd: {role} | {_n(w, 0)} | {c:.3f} % | {_n(c * 1e4 / w) if w else '–'} |")
    L.append("")
    return L


def idle_write_cause(idl):
    per = []
    for cnt, res in zip(idl.get("cnt_write", []), idl.get("sim_write", [])):
        if not cnt:
            continue
        n = max(_requests(res), 1)
        ctl, _ = control_thread(cnt)
        serving = serving_threads(cnt)
        f = {"cpu_us": cnt["cpu_s"] / n * 1e6, "wait_us": sum(t["wait_s"] for t in serving) / n * 1e6,
             "serving": len(serving), "cs": (cnt["vcs"] + cnt["ivcs"]) / n,
             "busy": cnt["busy_cores"], "p50": res["p50_us"], "p99": res["p99_us"]}
        if ctl:
            f["ctl_wakes"] = ctl["slices"] / n
            f["ctl_wait_us"] = ctl["wait_s"] / max(ctl["slices"], 1) * 1e6
        per.append(f)
    h = medians(per)
    if not h:
        return None
    s = [f"Measured while the writes ran (medians): per write homingd used {_n(h['cpu_us'])} µs CPU, "
         f"{_n(h['cs'], 1)} context switches, and its {_threads(h['serving'])} other than the control loop "
         f"waited {_n(h['wait_us'])} µs for a core"]
    if "ctl_wakes" in h:
        s[0] += (f"; its control thread woke {_n(h['ctl_wakes'], 1)} times per write and waited "
                 f"{_n(h['ctl_wait_us'])} µs per wake-up for a core")
    s[0] += f"; the machine was {h['busy']:.2f} of {NCPU} cores busy."
    gap = h["p99"] - h["p50"]
    s.append(f"The p99 is {_n(gap, 0)} µs above the p50 ({_n(h['p50'], 0)} µs); the mean CPU and run-queue wait "
             f"per write are {_n(h['cpu_us'] + h['wait_us'], 0)} µs together, so "
             + ("the tail is waiting beyond the mean: a wake-up delayed on the shared cores."
                if gap > h["cpu_us"] + h["wait_us"] else "the work and wait of an ordinary write explain the tail."))
    return " ".join(s)


# --- durable writes --------------------------------------------------------------

def durable_figures(dr):
    one, eight, bare = [], [], []
    for cnt1, res1, cnt8, res8, b in zip(dr.get("cnt_one", []), dr["homingd"], dr.get("cnt_eight", []), dr["eight"],
                                         dr["bare"]):
        if cnt1:
            one.append(per_request(cnt1, _requests(res1), self_counters(res1), res1.get("seconds"))
                       | {"p50": res1["p50_us"], "p99": res1["p99_us"]})
        if cnt8:
            eight.append(per_request(cnt8, _requests(res8), self_counters(res8), res8.get("seconds"))
                         | {"rps": res8["rps"]})
        sc = self_counters(b)
        if sc:
            n = max(b["commits"], 1)
            bare.append({"cpu_us": sc["cpu_s"] / n * 1e6, "kernel": kernel_share(sc["user_s"], sc["sys_s"]),
                         "cs": (sc["vcs"] + sc["ivcs"]) / n, "ivcs": sc["ivcs"] / n, "wait_us": sc["wait_s"] / n * 1e6,
                         "p50": b["p50_us"], "p99": b["p99_us"], "per_s": b["per_s"]})
    h1, h8, r = medians(one), medians(eight), medians(bare)
    if not h1 or not r:
        return None
    h1["profile"] = next((c["profile"] for c in dr.get("cnt_one", []) if c and c.get("profile")), None)
    return {"one": h1, "eight": h8, "bare": r}


def durable_cause(dr):
    f = durable_figures(dr)
    if not f:
        return None
    h, r = f["one"], f["bare"]
    s = [f"Measured in these rounds (medians): per acknowledged write homingd used {_n(h['cpu_us'])} µs CPU"
         f"{_kern(h['kernel'])}, {_n(h['cs'], 1)} context switches, and its {_threads(h['serving'])} other than "
         f"the control loop waited {_n(h['serving_wait_us'])} µs for a core; the client used "
         f"{_n(h.get('client_cpu_us'))} µs CPU. Per bare commit: {_n(r['cpu_us'])} µs CPU{_kern(r['kernel'])}"
         f", {_n(r['cs'], 1)} context switches, {_n(r['wait_us'])} µs waiting for a core."]
    gap = h["p50"] - r["p50"]
    cpu_more = h["cpu_us"] + (h.get("client_cpu_us") or 0) - r["cpu_us"]
    wait_more = h["serving_wait_us"] - r["wait_us"]
    s.append(f"The tail: homingd's p99 lies {_n(h['p99'] - h['p50'], 0)} µs above its p50, the bare commit's "
             f"{_n(r['p99'] - r['p50'], 0)} µs above its own.")
    if gap <= 0:
        s.append("A typical write (p50) costs no more than a bare commit here, so the difference is in the tail "
                 "alone: single slow writes, which the means above do not separate.")
    else:
        s.append(f"homingd's p50 exceeds the bare commit's by {_n(gap, 0)} µs; beyond the bare commit's, the write "
                 f"costs {_n(cpu_more, 0)} µs more CPU (server and client: one request in flight, so they add up) "
                 f"and {_n(wait_more, 0)} µs more run-queue wait.")
        if cpu_more + wait_more < 0.5 * gap:
            s.append("Most of the difference is neither: time asleep (the disk's flush, hand-offs between threads).")
        elif cpu_more >= wait_more:
            s.append("The larger share is CPU: the work around the commit (the Modbus round trip, the decision, the "
                     "audit row), not the disk.")
        else:
            s.append(f"The larger share is waiting for a core: the machine was {h['busy']:.2f} of {NCPU} cores "
                     f"busy, {h.get('others', 0):.2f} by other processes.")
    pr = h.get("profile")
    if pr:
        s.append(f"Profile of as many writes again after round 1's, untimed (perf record, cpu-clock, "
                 f"{pr['samples']} samples), homingd's CPU by system "
                 "call: " + ", ".join(f"{name} {share * 100:.0f} %" for name, share in
                                      sorted(pr["by_call"].items(), key=lambda x: -x[1])[:5]) + ".")
    return " ".join(s)


def durable8_cause(dr):
    f = durable_figures(dr)
    if not f or not f["eight"]:
        return None
    h, r = f["eight"], f["bare"]
    both = h["cpu_us"] + (h.get("client_cpu_us") or 0)
    left = max(NCPU - h.get("others", 0), 0.1)  # the cores other processes left to the benchmark
    ceiling = left / both * 1e6 if both else float("inf")
    s = [f"Measured in these rounds (medians), 8 writing clients: per write homingd used {_n(h['cpu_us'])} µs CPU"
         f"{_kern(h['kernel'])}, {_n(h['cs'], 1)} context switches, {_n(h['serving_wait_us'])} µs waiting "
         f"for a core in its {_threads(h['serving'])} other than the control loop; the clients "
         f"{_n(h.get('client_cpu_us'))} µs; the machine was {h['busy']:.2f} of {NCPU} "
         f"cores busy, {h.get('others', 0):.2f} by other processes. A bare commit: {_n(r['cpu_us'])} µs CPU, "
         f"{_n(1e6 / r['per_s'] if r['per_s'] else None, 0)} µs wall.",
         f"At {_n(both)} µs of CPU per write (server and clients) the {left:.2f} cores other processes left allow "
         f"at most {_n(ceiling, 0)} writes/s ({ceiling / r['per_s']:.2f}× the bare commit rate; all {NCPU} cores: "
         f"{NCPU * 1e6 / both / r['per_s']:.2f}×); measured {_n(h['rps'], 0)}."]
    if h["rps"] >= 0.8 * ceiling:
        s.append(f"So the CPU per write sets the rate, not the disk: 3× the bare rate on the whole machine needs at "
                 f"most {_n(NCPU * 1e6 / (3 * r['per_s']), 0)} µs of CPU per write, server and clients together.")
    else:
        s.append(f"The rate stays below what the CPU allows: the writes wait, {_n(h['serving_wait_us'])} µs per write "
                 f"for a core in homingd's {_threads(h['serving'])} other than the control loop, "
                 f"{_n(h['cs'], 1)} context "
                 "switches per write.")
    return " ".join(s)


def durable_table(dr):
    f = durable_figures(dr)
    if not f:
        return []
    L = ["Counters of the same rounds (medians; homingd's from `/proc` at the edges of each load, the bare commit "
         "and the clients count themselves), per write:",
         "",
         "| | CPU µs | kernel | ctx switches | run-queue wait µs (threads other than the control loop) "
         "| client CPU µs "
         "| cores busy (others) |",
         "|---|---:|---:|---:|---:|---:|---:|"]
    r = f["bare"]
    L.append(f"| bare SQLite commit | {_n(r['cpu_us'])} | {_pct(r['kernel'])} | {_n(r['cs'], 2)} | {_n(r['wait_us'])} "
             "| | |")
    for key, label in (("one", "**homingd**, 1 client"), ("eight", "**homingd**, 8 writing clients")):
        x = f[key]
        if x:
            L.append(f"| {label} | {_n(x['cpu_us'])} | {_pct(x['kernel'])} | {_n(x['cs'], 2)} "
                     f"| {_n(x['serving_wait_us'])} ({x['serving']:.0f}) "
                     f"| {_n(x.get('client_cpu_us'))} | {x['busy']:.2f} ({x.get('others', 0):.2f}) |")
    L.append("")
    return L


# --- the engine, errors, the repeatability figures ----------------------------------

def engine_cause(results):
    eb = results.get("engine_bench", {}).get("BM_EngineStep_SixAxesHoming")
    ru = results.get("engine_rusage")
    if not eb:
        return None
    wall, cpu = eb
    s = [f"Measured: one step {wall:.0f} ns wall, {cpu:.0f} ns CPU (Google Benchmark)"]
    if ru:
        s[0] += (f"; during the benchmark it was preempted {ru['ivcs']:.0f} times and the machine was "
                 f"{ru['busy']:.2f} of {NCPU} cores busy")
    s[0] += "."
    if wall > 1.1 * cpu:
        s.append("Wall time exceeds CPU time by more than 10 %: the step waited for a core, a contended "
                 "measurement rather than the engine's cost.")
    else:
        s.append("Wall and CPU time agree: the step's own work is the cost (profile `engine_step_bench` to see "
                 "where).")
    return " ".join(s)


def errors_cause(rows):
    xs = rows["homingd"]
    return (f"Measured by the load generator over the rounds: {sum(int(x['exceptions']) for x in xs)} Modbus "
            f"exceptions ({sum(int(x['exc06']) for x in xs)} of them 06, busy, not counted as errors), "
            f"{sum(int(x['transport_errors']) for x in xs)} transport errors, {sum(int(x['reconnects']) for x in xs)} "
            f"reconnects, {sum(int(x['idle_clients']) for x in xs)} clients never answered.")


def spread_cause(rep, text):
    """The expected spread from the sensor noise and the sampling period (an
    edge is seen up to one period late: latch speed × period, uniform)."""
    import re
    m = re.search(r"latch ([\d.]+) mm/min", text)
    p = re.search(r"period ([\d.]+) ms", text)
    if not m or not p:
        return None
    q_mm = float(m.group(1)) / 60 * float(p.group(1)) / 1000
    expected = (rep["noise"] ** 2 + q_mm ** 2 / 12) ** 0.5
    return (f"Measured: std dev {rep['sd'] * 1000:.2f} µm over the runs; from the sensor noise "
            f"({rep['noise'] * 1000:.2f} µm) and the period's sampling of the latch move ({q_mm * 1000:.2f} µm per "
            f"period, uniform) alone {expected * 1000:.2f} µm ({expected / rep['noise']:.3f}×) is expected; the "
            f"remaining {max(rep['sd'] ** 2 - expected ** 2, 0) ** 0.5 * 1000:.2f} µm comes from the homing itself.")


def cycle_cause(rep, text):
    import re
    sh = re.search(r"shortest\s+([\d.]+)\s+([\d.]+)", text)
    lo = re.search(r"longest\s+([\d.]+)\s+([\d.]+)", text)
    p = re.search(r"period ([\d.]+) ms", text)
    excess_ms = (rep["cycle"] - rep["minimum"]) * 1000
    s = f"Measured: a cycle lasts {excess_ms:.1f} ms longer than its time-optimal minimum on average"
    if p:
        s += f" ({excess_ms / float(p.group(1)):.0f} periods)"
    if sh and lo:
        s += (f"; the shortest {(float(sh.group(1)) - float(sh.group(2))) * 1000:.1f} ms, the longest "
              f"{(float(lo.group(1)) - float(lo.group(2))) * 1000:.1f} ms above theirs")
    return s + "."


def cause(key, results):
    """The measured cause of a missed target, or a sentence saying what was not measured."""
    kind, _, arg = key.partition("_")
    text = None
    try:
        if kind == "throughput":
            rows = results["throughput"][int(arg)]
            text = throughput_cause(int(arg), rows, statistics.median(x for x in rows["ratio_rps"] if x))
        elif kind == "p99":
            text = p99_cause(int(arg), results["throughput"][int(arg)])
        elif kind == "loop":
            text = loop_cause(int(arg), results["throughput"][int(arg)])
        elif kind == "errors":
            text = errors_cause(results["throughput"][int(arg)])
        elif key == "idle_cpu":
            text = idle_cause(results["idle"])
        elif key == "idle_write":
            text = idle_write_cause(results["idle"])
        elif key == "durable":
            text = durable_cause(results["durable"])
        elif key == "durable_8":
            text = durable8_cause(results["durable"])
        elif key == "engine":
            text = engine_cause(results)
        elif key == "spread":
            text = spread_cause(results["repeatability"], results["repeatability_text"])
        elif key == "cycle":
            text = cycle_cause(results["repeatability"], results["repeatability_text"])
    except (KeyError, ValueError, ZeroDivisionError, statistics.StatisticsError) as e:
        text = f"no cause: its counters are incomplete in this run ({type(e).__name__}: {e})."
    return text or "no cause: no counters were read for this target in this run."


# --- trying sections on their own (run_benchmarks.py --try) -------------------------

TRY_KEYS = {"throughput": lambda r: [f"{k}_{c}" for c in sorted(r["throughput"]) for k in ("throughput", "p99", "loop")]
            + [f"errors_{c}" for c in sorted(r["throughput"]) if c >= 64],
            "idle": lambda r: ["idle_cpu", "idle_write"], "durable": lambda r: ["durable", "durable_8"],
            "engine": lambda r: ["engine", "spread", "cycle"]}


def try_report(results, sections):
    """What the measured sections would print: their counter tables, and the
    cause each of their targets would get if it were missed."""
    L = []
    if "throughput" in sections:
        tp = results["throughput"]
        L += ["## throughput: counters", ""] + throughput_table(tp) + loop_table(tp)
    if "idle" in sections:
        L += ["## idle: counters", ""] + idle_table(results["idle"])
    if "durable" in sections:
        L += ["## durable: counters", ""] + durable_table(results["durable"])
    L += ["## causes (each target, met or not)", ""]
    for sec in sections:
        for key in TRY_KEYS.get(sec, lambda r: [])(results):
            L.append(f"- {key}: {cause(key, results)}")
    return "\n".join(L) + "\n"
