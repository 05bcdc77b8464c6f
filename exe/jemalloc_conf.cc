// Linked into cwloc-index with jemalloc (exe/CMakeLists.txt). jemalloc reads its options from
// this symbol when it starts: every arena on transparent huge pages, which Linux's default THP
// mode ("madvise") gives only where asked. A big model's millions of small arrays then fault in
// 2 MiB at a time instead of 4 KiB.
extern "C" {
extern const char* malloc_conf;
const char* malloc_conf = "thp:always,metadata_thp:always";
}
