"""What accuracy costs in time: work-precision runs, their references, pilot and records, timing,
scaling with the number of masses, and the reports of each."""
