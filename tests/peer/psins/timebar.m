function timebar(varargin)
% calbench's harness: PSINS's progress bar is a window; the run is headless.
end
