"""The benchmark: its tasks, the methods that plan them, runs kept on disk and resumed, their
results, the reference plans' check, the dataset importer and the speed measurements."""
