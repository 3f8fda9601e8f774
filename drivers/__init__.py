"""touchbench: drivers, the sources of signal samples.

``source``       the :class:`~drivers.source.Source` interface: blocks with their times
``replay``       :class:`~drivers.replay.FileReplaySource`: any recording file, block by
                 block (audio, ``.npy``, CSV, ROS bags), as fast as possible or paced
``bags``         audio_common audio in ROS 1 and ROS 2 bags (``rosbags``, no ROS install):
                 raw PCM or MP3; :func:`~drivers.bags.open_bag_source` picks a bag's source
``bag_fields``   numeric fields of any bag topic as channels, on an even grid
``bag_reader``   opening a bag and naming its topics (what both bag readers share)
``mp3``          MP3 arriving in pieces, decoded as a stream (libsndfile)
``resample``     uneven time stamps onto an even grid, and the note on their jitter
``sound``        :class:`~drivers.sound.SoundDeviceSource`: sound-card capture (PortAudio)
``files``        read a recording (WAV/FLAC/..., CSV, ``.npy``) whole into a :class:`Recording`
``simulated``    synthetic contact-microphone sessions with known touches
``oscillating``  a simulated actively oscillated link with a 3-axis accelerometer

Every problem is a :class:`drivers.errors.DriverError`.  Import from the modules themselves
(``from touchbench.drivers.recording import Recording``): the package imports nothing, so
that catching a driver's error does not load NumPy.
"""
