//! `render::release_free_host_memory` gives freed heap pages back to the system: the
//! editor calls it now and then because on a CPU adapter device buffers and kernel
//! compiles are heap allocations that glibc otherwise keeps (docs/RELIABILITY.md, Soak).
//! One test in its own process, so that no other test's allocations move the numbers.

#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[test]
fn freed_heap_pages_go_back_to_the_system() {
    const BLOCKS: usize = 2000;
    const BLOCK: usize = 100 * 1024; // under glibc's mmap threshold: from the heap
    let resident = || kiln::bench::memory().expect("/proc/self/status").0 as f64 / 1048576.0;
    // Big blocks, each followed by a small live one, so that freeing them leaves holes
    // inside the heap that glibc does not give back by itself.
    let mut big = Vec::with_capacity(BLOCKS);
    let mut pins = Vec::with_capacity(BLOCKS);
    for i in 0..BLOCKS {
        big.push(vec![i as u8 | 1; BLOCK]);
        pins.push(Box::new(i));
    }
    let filled = resident();
    drop(big);
    let freed = resident();
    kiln::render::release_free_host_memory();
    let released = resident();
    let total = (BLOCKS * BLOCK) as f64 / 1048576.0;
    assert!(
        freed > filled - 0.25 * total,
        "glibc gave the holes back by itself ({filled:.0} → {freed:.0} MiB): the test no longer \
         tests anything"
    );
    assert!(
        released < freed - 0.75 * total,
        "{total:.0} MiB freed, resident {filled:.0} → {freed:.0} MiB after the free and \
         {released:.0} MiB after the release"
    );
    assert_eq!(pins.len(), BLOCKS);
}
