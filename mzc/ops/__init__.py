"""The operations on surfaces and grids: cutting (slicing), densifying and triangulating."""
