#include "lod/block_loader.h"

#include <chrono>

#include "scene/input_error.h"

namespace cuberille::lod {

BlockLoader::BlockLoader(const voxel::CvoxReader& reader, double throttleMibPerSecond)
    : reader_(reader), throttleBytesPerSecond_(throttleMibPerSecond * 1024.0 * 1024.0), thread_([this] { run(); }) {}

BlockLoader::~BlockLoader() {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        stop_ = true;
    }
    wake_.notify_all();
    thread_.join();
}

void BlockLoader::replaceRequests(std::vector<BlockRequest> requests) {
    {
        std::lock_guard<std::mutex> lock(mutex_);
        queue_.assign(requests.begin(), requests.end());
    }
    wake_.notify_all();
    done_.notify_all();  // an emptied queue may be what a waiter waits for
}

std::vector<LoadedBlock> BlockLoader::takeCompleted() {
    std::lock_guard<std::mutex> lock(mutex_);
    std::vector<LoadedBlock> out;
    out.swap(completed_);
    return out;
}

bool BlockLoader::idle() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return queue_.empty() && !reading_ && completed_.empty();
}

void BlockLoader::waitForCompleted() const {
    std::unique_lock<std::mutex> lock(mutex_);
    done_.wait(lock, [&] { return !completed_.empty() || (queue_.empty() && !reading_); });
}

uint64_t BlockLoader::bytesRead() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return bytesRead_;
}

void BlockLoader::run() {
    for (;;) {
        BlockRequest request;
        {
            std::unique_lock<std::mutex> lock(mutex_);
            wake_.wait(lock, [&] { return stop_ || !queue_.empty(); });
            if (stop_) return;
            request = queue_.front();
            queue_.pop_front();
            reading_ = true;
        }
        const auto t0 = std::chrono::steady_clock::now();
        LoadedBlock r;
        r.block = request.block;
        r.parts = request.parts;
        try {
            r.data = reader_.load(request.block, request.parts);
            r.bytes = reader_.partBytes(request.block, request.parts);
        } catch (const scene::InputError& e) {
            r.error = e.what();
        }
        if (throttleBytesPerSecond_ > 0.0) {  // a slow disk: the read takes bytes / rate at least
            const auto due = t0 + std::chrono::duration<double>(double(r.bytes) / throttleBytesPerSecond_);
            std::this_thread::sleep_until(due);
        }
        {
            std::lock_guard<std::mutex> lock(mutex_);
            bytesRead_ += r.bytes;
            completed_.push_back(std::move(r));
            reading_ = false;
        }
        done_.notify_all();
    }
}

}  // namespace cuberille::lod
