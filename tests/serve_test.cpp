// `iqc serve`: the page on 127.0.0.1 only; "/" and "/version" exist and nothing else (the scene's own
// files included); editing a module the scene includes rebuilds the page (new version, new values); an
// error becomes a page that shows it with its location; fixing it brings the scene back.
#include <catch2/catch.hpp>

#include <httplib.h>
#include <ifaddrs.h>
#include <netinet/in.h>
#include <arpa/inet.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <thread>

#include "TestUtil.h"

using namespace iqc::test;
namespace fs = std::filesystem;

namespace {

struct Server {
    pid_t pid = -1;
    int port = 0;
    ~Server() {
        if (pid > 0) {
            kill(pid, SIGTERM);
            waitpid(pid, nullptr, 0);
        }
    }
};

// Saves a file the way editors do, whole: written beside it and renamed over it, so the server never
// reads half a save (a half-read file would be a real build, with its own version number).
void save(const std::string& name, const std::string& text) {
    fs::path tmp = write_temp(name + ".saving", text);
    fs::rename(tmp, temp_dir() / name);
}

std::string ring(const std::string& radius) {
    return "shape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\nr ∈ [0,3] default = " + radius + ": ring radius\n";
}

template <class F>
bool eventually(F f, double seconds = 5.0) {
    auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
    while (std::chrono::steady_clock::now() < end) {
        if (f()) return true;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    return f();
}

// Starts `iqc serve dir/scene.iq` on a free port polling every 50 ms; the port is known when it returns.
void start_serve(Server& s, const fs::path& dir) {
    fs::path out = dir / "stdout.txt";
    std::fflush(stdout);
    std::fflush(stderr);
    s.pid = fork();
    REQUIRE(s.pid >= 0);
    if (s.pid == 0) {
        FILE* f = std::freopen(out.c_str(), "w", stdout);
        (void)f;
        FILE* e = std::freopen((dir / "stderr.txt").c_str(), "w", stderr);
        (void)e;
        execl(IQC_BINARY, IQC_BINARY, "serve", (dir / "scene.iq").c_str(), "--port", "0", "--poll", "0.05",
              static_cast<char*>(nullptr));
        _exit(127);
    }
    REQUIRE(eventually([&] {
        std::string text = read_text(out);
        auto at = text.find("http://127.0.0.1:");
        if (at == std::string::npos) return false;
        s.port = std::stoi(text.substr(at + 17));
        return true;
    }, 30.0));
}

}  // namespace

TEST_CASE("iqc serve: loopback only, two paths, rebuilds on a module edit, shows errors", "[serve]") {
    fs::path dir = temp_dir() / "serve";
    fs::remove_all(dir);
    fs::create_directories(dir);
    write_temp("serve/ring.iql", ring("1"));
    write_temp("serve/scene.iq", "title = \"serve test\"\ninclude = [\"ring.iql\"]\n[[shapes]]\ntype = \"ring\"\n");
    Server s;
    start_serve(s, dir);
    INFO("port " << s.port);
    httplib::Client client("127.0.0.1", s.port);
    auto page = client.Get("/");
    REQUIRE(page);
    CHECK(page->status == 200);
    CHECK_THAT(page->body, Catch::Contains("id=\"iqc-shader\""));
    CHECK_THAT(page->body, Catch::Contains("fetch('/version'"));
    CHECK_THAT(page->body, Catch::Contains("ring radius"));
    auto v1 = client.Get("/version");
    REQUIRE(v1);
    CHECK(v1->body == "1");
    // Nothing but the page and its version: not the scene, not its modules, not a path outside.
    for (const char* path : {"/scene.iq", "/ring.iql", "/../scene.iq", "/%2e%2e/scene.iq", "/etc/passwd", "/index.html"}) {
        auto r = client.Get(path);
        REQUIRE(r);
        CHECK(r->status == 404);
    }
    // Loopback only: a non-loopback address of this machine refuses the connection.
    ifaddrs* addrs = nullptr;
    if (getifaddrs(&addrs) == 0) {
        for (ifaddrs* a = addrs; a; a = a->ifa_next) {
            if (!a->ifa_addr || a->ifa_addr->sa_family != AF_INET) continue;
            char ip[INET_ADDRSTRLEN];
            inet_ntop(AF_INET, &reinterpret_cast<sockaddr_in*>(a->ifa_addr)->sin_addr, ip, sizeof ip);
            if (std::string(ip).rfind("127.", 0) == 0) continue;
            httplib::Client other(ip, s.port);
            other.set_connection_timeout(1);
            INFO("address " << ip);
            CHECK(!other.Get("/version"));
        }
        freeifaddrs(addrs);
    }
    // Edit the included module: a new version whose page has the new default.
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    save("serve/ring.iql", ring("2.25"));
    CHECK(eventually([&] { auto r = client.Get("/version"); return r && r->body == "2"; }));
    auto page2 = client.Get("/");
    REQUIRE(page2);
    CHECK_THAT(page2->body, Catch::Contains("2.25"));
    // Break it: the page shows the diagnostic with its location instead of a blank canvas.
    save("serve/ring.iql", "shape\nD = ‖p‖ - radius\nwhere\np ∈ ℝ³\n");
    CHECK(eventually([&] { auto r = client.Get("/version"); return r && r->body == "3"; }));
    auto broken = client.Get("/");
    REQUIRE(broken);
    CHECK(broken->status == 200);
    CHECK_THAT(broken->body, Catch::Contains("\"error\":"));
    CHECK_THAT(broken->body, Catch::Contains("ring.iql:2:"));
    CHECK_THAT(broken->body, Catch::Contains("undefined name"));
    // Fix it: back to a working page.
    save("serve/ring.iql", ring("0.5"));
    CHECK(eventually([&] { auto r = client.Get("/version"); return r && r->body == "4"; }));
    auto fixed = client.Get("/");
    REQUIRE(fixed);
    CHECK_THAT(fixed->body, !Catch::Contains("\"error\":"));
}

TEST_CASE("iqc serve usage errors", "[serve]") {
    RunResult missing = run_iqc("serve /nonexistent/scene.iq --port 0");
    CHECK(missing.exit_code == 1);
    CHECK_THAT(missing.err, Catch::Contains("cannot read '/nonexistent/scene.iq'"));
    CHECK(run_iqc("serve").exit_code == 2);
    CHECK(run_iqc("serve x.iq --port 70000").exit_code == 2);
}

TEST_CASE("iqc serve: connections that never send do not stall it", "[serve]") {
    fs::path dir = temp_dir() / "serve_halfopen";
    fs::remove_all(dir);
    fs::create_directories(dir);
    write_temp("serve_halfopen/scene.iq", "[[shapes]]\ntype = \"sphere\"\n");
    Server s;
    start_serve(s, dir);
    // 40 connections that send nothing, 8 that send half a request and stop.
    std::vector<int> sockets;
    for (int i = 0; i < 48; ++i) {
        int fd = socket(AF_INET, SOCK_STREAM, 0);
        REQUIRE(fd >= 0);
        sockaddr_in addr{};
        addr.sin_family = AF_INET;
        addr.sin_port = htons(uint16_t(s.port));
        addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        REQUIRE(connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) == 0);
        if (i >= 40) {
            const char* partial = "GET /version HTTP/1.1\r\nHost: 127.0.0.1\r\n";
            REQUIRE(send(fd, partial, std::strlen(partial), 0) > 0);
        }
        sockets.push_back(fd);
    }
    httplib::Client client("127.0.0.1", s.port);
    client.set_read_timeout(10, 0);
    auto t0 = std::chrono::steady_clock::now();
    auto v = client.Get("/version");
    double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    REQUIRE(v);
    CHECK(v->body == "1");
    CHECK(seconds < 2.0);
    for (int fd : sockets) close(fd);
}

TEST_CASE("iqc serve: a save during a rebuild is picked up", "[serve]") {
    fs::path dir = temp_dir() / "serve_race";
    fs::remove_all(dir);
    fs::create_directories(dir);
    // A scene slow enough to compile (thousands of instances) that a second save lands during the rebuild
    // the first one started, after the rebuild has read the module.
    // (Shapes without parameters: WebGL2's uniform budget stays small.)
    std::string scene = "include = [\"ring.iql\"]\n[modules]\ndot = \"shape\\nD = ‖p‖ - 0.1\\nwhere\\np ∈ ℝ³\"\n"
                        "[[shapes]]\ntype = \"ring\"\n";
    for (int i = 0; i < 3000; ++i) scene += "[[shapes]]\ntype = \"dot\"\ntransform = \"T((" + std::to_string(i) + ", 0, 0))\"\n";
    write_temp("serve_race/ring.iql", ring("1"));
    write_temp("serve_race/scene.iq", scene);
    Server s;
    start_serve(s, dir);
    httplib::Client client("127.0.0.1", s.port);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    save("serve_race/ring.iql", ring("1.5"));
    // The poll (50 ms) starts a rebuild that reads ring.iql first and then compiles for a while.
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    save("serve_race/ring.iql", ring("2.75"));
    CHECK(eventually([&] {
        auto r = client.Get("/");
        return r && r->body.find("2.75") != std::string::npos;
    }, 60.0));
}

TEST_CASE("iqc serve: invalid UTF-8 in a description or an error keeps serving", "[serve]") {
    fs::path dir = temp_dir() / "serve_utf8";
    fs::remove_all(dir);
    fs::create_directories(dir);
    write_temp("serve_utf8/ring.iql", "shape\nD = ‖p‖ - r\nwhere\np ∈ ℝ³\nr ∈ [0,3] default = 1: bad \xFF byte\n");
    write_temp("serve_utf8/scene.iq", "include = [\"ring.iql\"]\n[[shapes]]\ntype = \"ring\"\n");
    Server s;
    start_serve(s, dir);
    httplib::Client client("127.0.0.1", s.port);
    auto page = client.Get("/");
    REQUIRE(page);
    CHECK_THAT(page->body, Catch::Contains("bad \xEF\xBF\xBD byte"));
    save("serve_utf8/ring.iql", "shape\nD = ‖p‖ - \xFF\xFE\nwhere\np ∈ ℝ³\n");
    CHECK(eventually([&] { auto r = client.Get("/version"); return r && r->body == "2"; }));
    auto broken = client.Get("/");
    REQUIRE(broken);
    CHECK_THAT(broken->body, Catch::Contains("\"error\":"));
    CHECK_THAT(broken->body, Catch::Contains("ring.iql:2:"));
}
