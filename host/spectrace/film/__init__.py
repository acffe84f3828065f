"""The film: what a render integrates against and what it gives back.

- `response`: what the film responds to (colour matching functions, a measured sensor's curves), the wavelength
  range and the sampling table the kernels read;
- `aovs`: the images kept beside the colour (albedo, normal, depth...), their names and channels;
- `state`: the film's saved state (what checkpoints and tiles hold), its checks and its image;
- `setup`: the one object the engine asks for the film's defines, device buffers (`Film`) and kernel arguments,
  and which reads the result back into an `Image`;
- `image`: the public `Image` (`spectrace.Image`); `colour_output` and `output_options`: how it becomes files.

The package imports nothing itself: the scene loader reads `response` and `aovs` without the device layer that
`setup` needs.
"""
