# Registers SOURCE onto TARGET (files, (N, 3) arrays or quadrix.Cloud objects) and prints the result.
import sys
import quadrix
result = quadrix.register(sys.argv[1], sys.argv[2])  # preset="auto", config=None, refiner=None
print(result.transform)  # 4x4 NumPy array: maps source points into the target frame
print(result.status, result.message, result.counts["correspondences"], result.timings_ms["total"])
