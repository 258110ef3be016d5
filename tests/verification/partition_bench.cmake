# The partition-quality benchmark of the refinement (bench/bench_partition.py, issue 51): its
# parts' known answers and a reduced run (the main job at 6 mm on 2 ranks, 16 and 64 ranks)
# with the 2:1 balance and the partitions' invariants (~20 s; asserts no wall time).
mpm_add_script_test(test_partition_bench SCRIPT verification/test_partition_bench.py
                    LABELS benchmark TIMEOUT 300)
