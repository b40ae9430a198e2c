#include "driver/Serve.h"

#include <httplib.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <thread>
#include <vector>

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
    // What the compile read: each real file's text as the compile saw it (nullopt: it could not be read).
    // The watcher compares contents, not modification times: times are coarse on some file systems and a
    // save during a compile is then still seen (the disk differs from what was compiled).
    std::map<std::string, std::optional<std::string>> files;
    bool ok = false;
};

std::optional<std::string> read_all(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return std::nullopt;
    std::ostringstream ss;
    ss << in.rdbuf();
    return ss.str();
}

std::string live_reload_script(unsigned version, double poll_seconds) {
    // Polls /version; a different number means a new build: reload (sliders live in sessionStorage).
    return "const iqcVersion = " + std::to_string(version) +
           ";\n  setInterval(() => fetch('/version', { cache: 'no-store' }).then(r => r.text()).then(v => {\n"
           "    if (Number(v) !== iqcVersion) location.reload();\n  }).catch(() => {}), " +
           std::to_string(static_cast<int>(poll_seconds * 1000)) + ");";
}

// Compiles the input to its page and records the text of every file the compile read.
Build build(const std::string& input, unsigned version, double poll_seconds) {
    Build b;
    SourceManager sm;
    Diagnostics diags(sm);
    CompileOptions opts;
    opts.target = Target::WebGL2;
    CompileResult r;
    try {
        r = compile_file(input, sm, diags, opts);
    } catch (const std::exception& e) {  // a bug in iqc: shown in the page, the server keeps running
        r.exit_code = 3;
        r.internal = std::string("internal compiler error: ") + e.what() + " (this is a bug in iqc)";
    }
    // Watch every real file the compile read (modules beside the scene, includes), and the input itself
    // (also when it could not be read: its creation then rebuilds).
    for (size_t f = 0; f < sm.size(); ++f) {
        const std::string& name = sm.name(static_cast<FileId>(f));
        std::error_code ec;
        if (b.files.count(name) || !fs::is_regular_file(name, ec)) continue;
        b.files[name] = std::string(sm.text(static_cast<FileId>(f)));
    }
    if (!b.files.count(input)) b.files[input] = read_all(input);
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
    Build current = build(input, version, poll_seconds);
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
            std::vector<std::string> paths;
            {
                std::lock_guard<std::mutex> lock(mu);
                for (const auto& [path, text] : current.files) {
                    paths.push_back(path);
                    if (!changed && read_all(path) != text) changed = true;
                }
            }
            if (!changed) continue;
            // A save in progress (many editors truncate, then write) reads as an empty or half file: wait until
            // two reads 50 ms apart agree before compiling (at most a second).
            std::vector<std::optional<std::string>> before;
            for (int tries = 0; tries < 20; ++tries) {
                std::vector<std::optional<std::string>> now;
                for (const auto& path : paths) now.push_back(read_all(path));
                if (tries > 0 && now == before) break;
                before = std::move(now);
                std::this_thread::sleep_for(std::chrono::milliseconds(50));
            }
            auto t0 = std::chrono::steady_clock::now();
            Build next = build(input, version + 1, poll_seconds);
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
