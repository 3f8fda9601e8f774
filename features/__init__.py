"""touchbench: features, from signal arrays to feature arrays and names.

Feature functions follow librosa's conventions: keyword-only parameters after the
signal, channel axis first and frame axis last, vectorised over frames, one error type
(:class:`features.errors.FeatureError`).

``framing``   frames, STFT, power spectrogram, bin frequencies
``temporal``  RMS, zero crossings, peak level
``spectral``  centroid, roll-off, flux, band peak and prominence
``pitch``     FFT peak, autocorrelation, Larson-Maddox wavelet tracker
``mel``       mel filter bank, MFCC
``snr``       SNR against a tracked noise floor, touches
``stats``     per-event mean, minimum, maximum, range
``events``    event detection: ``snr``, ``dbscan``, ``none``
``extractors`` the named extractors (``uc3m-audio``, ``band-peaks``, ``mfcc``,
              ``taxel-dft``, ``window``, ``sequence``) and their registry
``resample``  sequences to a fixed number of steps
``snr_stream``, ``event_streams``  the tracker and the detectors fed block by block
``stream``    the streaming engine: blocks in, instances out as events end
``history``   the bounded history of samples (and windows) a stream keeps
``recipe``    extractor + detector + options as JSON: what a model repeats live
"""
