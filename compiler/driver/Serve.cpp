#include "driver/Serve.h"

#include <httplib.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <thread>

#include <nlohmann/json.hpp>

#include "scene/Compile.h"
#include "scene/Page.h"
#include "source/Source.h"

namespace iqc {

namespace fs = std::filesystem;

namespace {

constexpr size_t kServeThreads = 32;

struct Build {
    std::string page;
    std::map<std::string, fs::file_time_type> files;  // what the compile read, with its time
    bool ok = false;
};

fs::file_time_type mtime(const std::string& path) {
    std::error_code ec;
    auto t = fs::last_write_time(path, ec);
    return ec ? fs::file_time_type::min() : t;
}

std::string live_reload_script(unsigned version, double poll_seconds) {
    // Polls /version; a different number means a new build: reload (sliders live in sessionStorage).
    return "const iqcVersion = " + std::to_string(version) +
           ";\n  setInterval(() => fetch('/version', { cache: 'no-store' }).then(r => r.text()).then(v => {\n"
           "    if (Number(v) !== iqcVersion) location.reload();\n  }).catch(() => {}), " +
           std::to_string(static_cast<int>(poll_seconds * 1000)) + ");";
}

// Compiles the input to its page. `before`: the files the previous build read, with their times taken
// now, before this compile reads them; a save during the compile then differs from what is recorded
// and the next poll rebuilds (recording times after the compile missed such saves).
Build build(const std::string& input, unsigned version, double poll_seconds,
            const std::map<std::string, fs::file_time_type>& before) {
    Build b;
    SourceManager sm;
    Diagnostics diags(sm);
    CompileOptions opts;
    opts.target = Target::WebGL2;
    auto start = fs::file_time_type::clock::now();
    CompileResult r;
    try {
        r = compile_file(input, sm, diags, opts);
    } catch (const std::exception& e) {  // a bug in iqc: shown in the page, the server keeps running
        r.exit_code = 3;
        r.internal = std::string("internal compiler error: ") + e.what() + " (this is a bug in iqc)";
    }
    // Watch every real file the compile read (modules beside the scene, includes), and the input itself.
    // A file read for the first time has no earlier time: if it changed since shortly before this compile
    // began (file systems stamp times coarsely), it is marked changed so the next poll rebuilds once.
    std::vector<std::string> read = {input};
    for (size_t f = 0; f < sm.size(); ++f) read.push_back(sm.name(static_cast<FileId>(f)));
    for (const std::string& name : read) {
        std::error_code ec;
        if (!fs::is_regular_file(name, ec)) continue;
        if (auto it = before.find(name); it != before.end()) {
            b.files[name] = it->second;
        } else {
            fs::file_time_type t = mtime(name);
            b.files[name] = t >= start - std::chrono::seconds(2) ? fs::file_time_type::min() : t;
        }
    }
    std::string live = live_reload_script(version, poll_seconds);
    if (r.exit_code == 0) {
        b.page = html_page(r.code, r.meta, live);
        b.ok = true;
    } else {
        std::string text = diags.render();
        if (r.exit_code == 3) text += r.internal;
        nlohmann::json meta = {{"title", fs::path(input).filename().string()}, {"error", text}};
        b.page = html_page("", meta.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), live);
    }
    return b;
}

}  // namespace

int serve(const std::string& input, int port, double poll_seconds) {
    std::error_code ec;
    if (!fs::is_regular_file(input, ec)) {
        std::fprintf(stderr, "iqc: error: cannot read '%s'\n", input.c_str());
        return 1;
    }
    std::mutex mu;
    std::atomic<unsigned> version{1};
    Build current = build(input, version, poll_seconds, {{input, mtime(input)}});
    if (!current.ok) std::fprintf(stderr, "iqc: %s has errors (shown in the page)\n", input.c_str());

    httplib::Server server;
    // Requests are tiny GETs from this machine: short timeouts and enough threads, so connections that
    // never send (or never read) hold a thread for a second, not the server for the default 5 s each.
    server.new_task_queue = [] { return new httplib::ThreadPool(kServeThreads); };
    server.set_read_timeout(1, 0);
    server.set_write_timeout(1, 0);
    server.set_keep_alive_timeout(1);
    server.set_keep_alive_max_count(100);
    server.set_payload_max_length(4096);
    server.Get("/", [&](const httplib::Request&, httplib::Response& res) {
        std::lock_guard<std::mutex> lock(mu);
        res.set_header("Cache-Control", "no-store");
        res.set_content(current.page, "text/html; charset=utf-8");
    });
    server.Get("/version", [&](const httplib::Request&, httplib::Response& res) {
        res.set_header("Cache-Control", "no-store");
        res.set_content(std::to_string(version.load()), "text/plain");
    });
    // Loopback only: the page is for the person at this machine.
    const char* host = "127.0.0.1";
    int bound = port == 0 ? server.bind_to_any_port(host) : (server.bind_to_port(host, port) ? port : -1);
    if (bound < 0) {
        std::fprintf(stderr, "iqc: error: cannot listen on %s:%d\n", host, port);
        return 1;
    }
    std::printf("iqc: serving %s at http://%s:%d/ (Ctrl-C stops)\n", input.c_str(), host, bound);
    std::fflush(stdout);

    std::atomic<bool> running{true};
    std::thread watcher([&] {
        while (running) {
            std::this_thread::sleep_for(std::chrono::duration<double>(poll_seconds));
            bool changed = false;
            std::map<std::string, fs::file_time_type> now;  // taken before the rebuild reads the files
            {
                std::lock_guard<std::mutex> lock(mu);
                for (const auto& [path, t] : current.files) {
                    now[path] = mtime(path);
                    if (now[path] != t) changed = true;
                }
            }
            if (!changed) continue;
            auto t0 = std::chrono::steady_clock::now();
            Build next = build(input, version + 1, poll_seconds, now);
            {
                std::lock_guard<std::mutex> lock(mu);
                current = std::move(next);
                ++version;
            }
            double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
            std::fprintf(stderr, "iqc: rebuilt (version %u, %s, %.1f ms)\n", version.load(),
                         current.ok ? "ok" : "errors shown in the page", ms);
        }
    });
    server.listen_after_bind();
    running = false;
    watcher.join();
    return 0;
}

}  // namespace iqc
